//! Engine tests on small analytic inputs (the guide module's own tests cover guides).

use super::*;
use crate::img::Plane;
use glam::Vec2;

/// Analytic guides of a disc (center c, radius r) growing by `v` px per frame at frame k.
pub(crate) fn disc_guides(w: usize, h: usize, c: Vec2, r: f32, v: f32, k: usize, frames: usize) -> FrameGuides {
    let dist = Plane::from_fn(w, h, |x, y| r - (Vec2::new(x as f32, y as f32) - c).length());
    let mask = dist.map(|d| d >= 0.0);
    let flow = Plane::from_fn(w, h, |x, y| {
        let d = Vec2::new(x as f32, y as f32) - c;
        let l = d.length().max(1e-3);
        d / l * v * (l / r).min(1.0)
    });
    // ext+: motion accumulated since the paint arrived; ext−: to the end.
    let ext_pos = Plane::from_fn(w, h, |x, y| {
        let l = (Vec2::new(x as f32, y as f32) - c).length();
        if l > r { 0.0 } else { (k as f32 * v * (l / r)).min((r - l).max(0.0) + 0.0) }
    });
    let ext_neg = Plane::from_fn(w, h, |x, y| {
        let l = (Vec2::new(x as f32, y as f32) - c).length();
        if l > r { 0.0 } else { (frames - 1 - k) as f32 * v * (l / r) }
    });
    FrameGuides { mask, dist, flow, ext_pos, ext_neg }
}

/// A textured exemplar: a growing disc of noisy "paint" on white paper.
pub(crate) fn disc_exemplar(w: usize, h: usize, frames: usize, seed: u64) -> (Vec<Plane<Rgb>>, Vec<FrameGuides>) {
    let c = Vec2::new(w as f32 / 2.0, h as f32 / 2.0);
    let mut rng = Rng::keyed(&[seed]);
    let noise = img::gaussian_blur(&Plane::from_fn(w, h, |_, _| rng.f32()), 1.2);
    let mut rgb = Vec::new();
    let mut g = Vec::new();
    for k in 0..frames {
        let r = w.min(h) as f32 * (0.2 + 0.02 * k as f32);
        let gk = disc_guides(w, h, c, r, w.min(h) as f32 * 0.02, k, frames);
        let f = Plane::from_fn(w, h, |x, y| {
            if gk.mask.get(x, y) {
                let n = noise.get(x, y);
                let rim = (1.0 - gk.dist.get(x, y) / 6.0).clamp(0.0, 1.0);
                let d = 0.35 + 0.5 * n + 0.2 * rim;
                [1.0 - 0.8 * d, 1.0 - 0.5 * d, 1.0 - 0.1 * d]
            } else {
                [1.0, 1.0, 1.0]
            }
        });
        rgb.push(f);
        g.push(gk);
    }
    (rgb, g)
}

fn psnr(a: &Plane<Rgb>, b: &Plane<Rgb>, mask: &Mask) -> f64 {
    let mut se = 0.0f64;
    let mut n = 0usize;
    for ((x, y), &m) in a.data().iter().zip(b.data()).zip(mask.data()) {
        if m {
            for k in 0..3 {
                se += ((x[k] - y[k]) as f64).powi(2);
            }
            n += 3;
        }
    }
    10.0 * (1.0 / (se / n as f64)).log10()
}

#[test]
fn identity_reproduces_the_exemplar() {
    let (rgb, g) = disc_exemplar(64, 64, 6, 1);
    let params = Params::builder().seed(3).build().unwrap();
    let source = Source::from_parts(&rgb, &g, &params, 6.0).unwrap();
    let mut s = Synthesizer::new(source, params).unwrap();
    let mut scores = Vec::new();
    for k in 0..g.len() {
        let out = s.step(&g[k]).unwrap();
        scores.push(psnr(&out.rgb, &rgb[k], &g[k].mask));
    }
    eprintln!("identity PSNR per frame: {:?}", scores);
    assert!(scores.iter().all(|&p| p > 25.0), "{:?}", scores);
}

#[test]
fn resume_from_checkpoint_matches_uninterrupted_run() {
    let (rgb, g) = disc_exemplar(48, 48, 5, 2);
    let params = Params::builder().seed(9).build().unwrap();
    let source = Source::from_parts(&rgb, &g, &params, 5.0).unwrap();
    let target: Vec<FrameGuides> =
        (0..4).map(|k| disc_guides(56, 40, Vec2::new(24.0 + 2.0 * k as f32, 20.0), 12.0, 2.0, k, 4)).collect();
    let mut a = Synthesizer::new(source.clone(), params.clone()).unwrap();
    let full: Vec<_> = target.iter().map(|t| a.step(t).unwrap().rgb).collect();
    let mut b = Synthesizer::new(source.clone(), params.clone()).unwrap();
    b.step(&target[0]).unwrap();
    b.step(&target[1]).unwrap();
    let state = b.save_state();
    let mut c = Synthesizer::new(source.clone(), params.clone()).unwrap();
    c.load_state(&state, std::path::Path::new("state")).unwrap();
    assert_eq!(c.frame(), 2);
    assert_eq!(c.step(&target[2]).unwrap().rgb, full[2]);
    assert_eq!(c.step(&target[3]).unwrap().rgb, full[3]);
    // A checkpoint from other parameters is refused, and garbage too.
    let other = Params::builder().seed(10).build().unwrap();
    let mut d = Synthesizer::new(source.clone(), other).unwrap();
    assert!(d.load_state(&state, std::path::Path::new("state")).is_err());
    assert!(c.load_state(&state[..state.len() / 2], std::path::Path::new("state")).is_err());
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let (rgb, g) = disc_exemplar(48, 48, 5, 4);
    let params = Params::builder().seed(11).build().unwrap();
    let source = Source::from_parts(&rgb, &g, &params, 5.0).unwrap();
    // Tall enough for several PatchMatch tiles.
    let target: Vec<FrameGuides> =
        (0..3).map(|k| disc_guides(60, 90, Vec2::new(30.0, 40.0 + 3.0 * k as f32), 25.0, 3.0, k, 3)).collect();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut s = Synthesizer::new(source.clone(), params.clone()).unwrap();
            target.iter().map(|t| s.step(t).unwrap().rgb).collect::<Vec<_>>()
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}
