//! Measured properties of the flow and motion-extent guides on synthetic sequences (issue 3).

use fluidymation::guide::{FrameGuides, GuideParams, compute_sequence};
use fluidymation::img::Plane;
use glam::Vec2;

/// Coverage of a disc, anti-aliased by 4×4 supersampling.
fn disc(w: usize, h: usize, c: Vec2, r: f32) -> Plane<f32> {
    Plane::from_fn(w, h, |x, y| {
        let mut n = 0;
        for sy in 0..4 {
            for sx in 0..4 {
                let p = Vec2::new(x as f32 + (sx as f32 + 0.5) / 4.0 - 0.5, y as f32 + (sy as f32 + 0.5) / 4.0 - 0.5);
                if (p - c).length() < r {
                    n += 1;
                }
            }
        }
        n as f32 / 16.0
    })
}

fn boundary(g: &FrameGuides) -> Vec<(usize, usize)> {
    let (w, h) = g.size();
    let m = &g.mask;
    let mut v = Vec::new();
    for y in 0..h {
        for x in 0..w {
            if m.get(x, y) {
                let out = (x > 0 && !m.get(x - 1, y))
                    || (x + 1 < w && !m.get(x + 1, y))
                    || (y > 0 && !m.get(x, y - 1))
                    || (y + 1 < h && !m.get(x, y + 1));
                if out {
                    v.push((x, y));
                }
            }
        }
    }
    v
}

/// Frames far enough from both ends that the temporal windows are complete.
fn middle(n: usize, p: &GuideParams) -> std::ops::Range<usize> {
    let margin = (3.0 * p.time_blur_sigma).ceil() as usize + p.flow_time_radius + 2;
    margin..n - margin
}

#[test]
fn growing_disc_flows_outward_at_its_speed() {
    let (w, h, n, v) = (160, 160, 32, 1.5f32);
    let c = Vec2::new(80.0, 80.0);
    let seq: Vec<_> = (0..n).map(|i| disc(w, h, c, 15.0 + v * i as f32)).collect();
    let p = GuideParams::default();
    let g = compute_sequence(&seq, &p).unwrap();
    let (mut worst_mag, mut worst_cos, mut sum, mut count) = (0f32, 1f32, 0f32, 0);
    for i in middle(n, &p) {
        for (x, y) in boundary(&g[i]) {
            let f = g[i].flow.get(x, y);
            let radial = (Vec2::new(x as f32, y as f32) - c).normalize();
            worst_mag = worst_mag.max((f.length() - v).abs() / v);
            worst_cos = worst_cos.min(f.normalize_or_zero().dot(radial));
            sum += f.length();
            count += 1;
        }
    }
    eprintln!(
        "growing disc: {count} boundary samples, mean |flow| {:.4} (v = {v}), worst magnitude error {:.1} %, worst cos to radial {:.4}",
        sum / count as f32,
        100.0 * worst_mag,
        worst_cos
    );
    assert!(worst_mag <= 0.10, "magnitude error {worst_mag}");
    assert!(worst_cos >= 0.98, "direction {worst_cos}");
}

#[test]
fn translating_disc_moves_its_interior_with_it() {
    let (w, h, n) = (150, 110, 32);
    let v = Vec2::new(1.2, 0.6);
    let seq: Vec<_> = (0..n).map(|i| disc(w, h, Vec2::new(35.0, 40.0) + v * i as f32, 20.0)).collect();
    let p = GuideParams::default();
    let g = compute_sequence(&seq, &p).unwrap();
    let (mut worst, mut count) = (0f32, 0);
    for i in middle(n, &p) {
        for y in 0..h {
            for x in 0..w {
                if g[i].dist.get(x, y) > 6.0 {
                    let e = (g[i].flow.get(x, y) - v).length() / v.length();
                    worst = worst.max(e);
                    count += 1;
                }
            }
        }
    }
    eprintln!("translating disc: {count} interior samples (dist > 6 px), worst |flow − v|/|v| {:.1} %", 100.0 * worst);
    assert!(worst <= 0.15, "{worst}");
}

/// An irregular, deforming blob: a disc plus a lobe, moving and growing with `t`.
fn blob(w: usize, h: usize, t: f32) -> Plane<f32> {
    let a = disc(w, h, Vec2::new(40.0 + 0.8 * t, 45.0 + 0.3 * t), 16.0 + 0.4 * t);
    let b = disc(w, h, Vec2::new(62.0 + 0.2 * t, 38.0 + 0.9 * t), 10.0 + 0.2 * t);
    Plane::from_fn(w, h, |x, y| a.get(x, y).max(b.get(x, y)))
}

#[test]
fn static_mask_has_no_flow_and_no_extent() {
    let frame = blob(100, 90, 5.0);
    let seq = vec![frame; 12];
    let g = compute_sequence(&seq, &GuideParams::default()).unwrap();
    let max_flow = g.iter().flat_map(|f| f.flow.data().iter().map(|v| v.length())).fold(0f32, f32::max);
    let max_ext = g.iter().flat_map(|f| f.ext_pos.data().iter().chain(f.ext_neg.data())).fold(0f32, |a, &b| a.max(b));
    eprintln!("static mask: max |flow| {max_flow}, max ext± {max_ext}");
    assert!(g[0].mask.count() > 500);
    assert_eq!(max_flow, 0.0);
    assert_eq!(max_ext, 0.0);
}

#[test]
fn forward_then_backward_motion_returns_ext_pos_to_zero() {
    let (w, h, m) = (150, 80, 12);
    let n = 2 * m + 1;
    let pos = |i: usize| 40.0 + 2.0 * (if i <= m { i } else { 2 * m - i }) as f32;
    let seq: Vec<_> = (0..n).map(|i| disc(w, h, Vec2::new(pos(i), 40.0), 22.0)).collect();
    let g = compute_sequence(&seq, &GuideParams::default()).unwrap();
    // Pixels covered in every frame: their accumulators never reset.
    let always = |x: usize, y: usize| g.iter().all(|f| f.mask.get(x, y));
    let (mut peak, mut end, mut count) = (0f32, 0f32, 0);
    for y in 0..h {
        for x in 0..w {
            if always(x, y) {
                peak = peak.max(g[m].ext_pos.get(x, y));
                end = end.max(g[n - 1].ext_pos.get(x, y));
                count += 1;
            }
        }
    }
    eprintln!(
        "forward-then-back: {count} pixels always inside; max ext+ at the turn {peak:.2} px, at the end {end:.3} px"
    );
    let mut ends: Vec<f32> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| always(x, y))
        .map(|(x, y)| g[n - 1].ext_pos.get(x, y))
        .collect();
    ends.sort_by(f32::total_cmp);
    let median = ends[ends.len() / 2];
    eprintln!("  median at the end {median:.3} px (accumulating norms instead would give ≥ {:.1} px)", 2.0 * peak);
    // Measured: at the end 0.692 px at most, median 0.015 px, of a peak of 20.34 px (the disc
    // moves 24 px to the turn). With the forward difference they were 1.382 and 0.525 px: its
    // second-order shortfall at the rim (|u_t|²/2r per frame) has the same sign both ways. With
    // the replicated ends of the sequence averaged into the first and last frames' windows,
    // 0.290 and 0.221 px of a peak of 18.94 px: the first frames' motion was under-reported.
    // What is left at the rim is the ends, where the speed is a one-sided difference. Bounds
    // 0.04 and 0.02 of the peak (0.81 and 0.41 px), the peak over 19 px.
    assert!(count > 100);
    assert!(peak > 19.0, "{peak}");
    assert!(end < 0.04 * peak, "{end} vs {peak}");
    assert!(median < 0.02 * peak, "{median} vs {peak}");
}

#[test]
fn ext_neg_is_ext_pos_of_the_reversed_sequence() {
    let (w, h, n) = (110, 100, 24);
    let seq: Vec<_> = (0..n).map(|i| blob(w, h, i as f32)).collect();
    let rev: Vec<_> = seq.iter().rev().cloned().collect();
    let p = GuideParams::default();
    let g = compute_sequence(&seq, &p).unwrap();
    let r = compute_sequence(&rev, &p).unwrap();
    let (mut sum_diff, mut sum, mut worst, mut count) = (0f64, 0f64, 0f32, 0);
    for i in 0..n {
        let (a, b) = (&g[i].ext_neg, &r[n - 1 - i].ext_pos);
        assert_eq!(g[i].mask, r[n - 1 - i].mask);
        for y in 0..h {
            for x in 0..w {
                if g[i].mask.get(x, y) {
                    let d = (a.get(x, y) - b.get(x, y)).abs();
                    sum_diff += d as f64;
                    sum += a.get(x, y) as f64;
                    worst = worst.max(d);
                    count += 1;
                }
            }
        }
    }
    let mean = sum / count as f64;
    let mean_diff = sum_diff / count as f64;
    eprintln!(
        "reversal: {count} samples, mean ext− {mean:.3} px, mean |ext− − ext+(reversed)| {mean_diff:.4} px, worst {worst:.3} px"
    );
    assert!(mean > 3.0);
    assert!(mean_diff < 0.05 * mean, "{mean_diff} vs {mean}");
}

/// A bar `2r` thick from `a` to `b` with round ends, anti-aliased by 4×4 supersampling.
fn capsule(w: usize, h: usize, a: Vec2, b: Vec2, r: f32) -> Plane<f32> {
    let ab = b - a;
    Plane::from_fn(w, h, |x, y| {
        let mut n = 0;
        for sy in 0..4 {
            for sx in 0..4 {
                let p = Vec2::new(x as f32 + (sx as f32 + 0.5) / 4.0 - 0.5, y as f32 + (sy as f32 + 0.5) / 4.0 - 0.5);
                let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                if (p - (a + t * ab)).length() < r {
                    n += 1;
                }
            }
        }
        n as f32 / 16.0
    })
}

/// A part thinner than the distance it moves in a few frames — an arm, a leg — is where the
/// distance fields stop measuring the motion: past the part's middle they count from its other
/// edge. A 12-px bar moving 8 px a frame across itself must still get its speed: measured 98 %
/// of it along the motion, mean error 0.22 px (0.86 px with the forward difference, whose
/// error was at the round ends, where the nearest edge of the next frame is not along the
/// normal; 91 % and 1.06 px before the flow's slope division and rigid fit, 2026-12-06); before
/// each boundary pixel's window was cut to the frames that fit (`flow::Task::estimate_at`),
/// 28 % and 5.77 px. Bounds 0.9 and 0.4 px.
#[test]
fn a_thin_fast_bar_keeps_its_speed() {
    let (w, h, n) = (160, 340, 32);
    let v = Vec2::new(0.0, 8.0);
    let seq: Vec<_> = (0..n)
        .map(|i| capsule(w, h, Vec2::new(20.0, 30.0) + v * i as f32, Vec2::new(140.0, 30.0) + v * i as f32, 6.0))
        .collect();
    let p = GuideParams::default();
    let g = compute_sequence(&seq, &p).unwrap();
    let (mut along, mut err, mut count) = (0f64, 0f64, 0f64);
    for i in middle(n, &p) {
        for y in 0..h {
            for x in 0..w {
                if g[i].mask.get(x, y) {
                    let f = g[i].flow.get(x, y);
                    along += (f.dot(v) / v.length_squared()) as f64;
                    err += (f - v).length() as f64;
                    count += 1.0;
                }
            }
        }
    }
    let (along, err) = (along / count, err / count);
    eprintln!("thin bar at 8 px/frame: flow along the motion {:.0} % of it, mean error {err:.2} px", 100.0 * along);
    assert!(along > 0.9 && err < 0.4, "{along} {err}");
}

/// Mean flow error (pixels) inside the mask of the quality suite's generated `kind` against its
/// known motion, over the flows `k` (the motion k → k + 1) that `which(k)` picks, and the mean
/// speed.
fn flow_error(kind: fluidymation::quality::TargetKind, frames: usize, which: impl Fn(usize) -> bool) -> (f32, f32) {
    let t = fluidymation::quality::Target::new(kind, 512, frames);
    let cov: Vec<Plane<f32>> = (0..frames).map(|k| t.coverage(k)).collect();
    let g = compute_sequence(&cov, &GuideParams::default()).unwrap();
    let (mut err, mut speed, mut n) = (0f64, 0f64, 0f64);
    for (k, f) in g.iter().enumerate().take(frames - 1).filter(|&(k, _)| which(k)) {
        let (w, h) = f.mask.size();
        for y in 0..h {
            for x in 0..w {
                if !f.mask.get(x, y) {
                    continue;
                }
                // flow(k) is the motion k → k + 1: the target's motion at frame k + 1.
                let m = t.motion(k + 1, x, y).unwrap();
                err += (f.flow.get(x, y) - m).length() as f64;
                speed += m.length() as f64;
                n += 1.0;
            }
        }
    }
    ((err / n) as f32, (speed / n) as f32)
}

/// The flow the masks give against the shapes' whole motion (24 frames, 512²). Measured, mean
/// error per pixel: translating 0.094 px of 3.10 px/frame (0.093 with the forward difference
/// and the flows smoothed over time at the pixel, 0.167 before the speed was divided by the
/// smoothed field's slope), growing 0.051 of 2.44 (0.058, 0.097), turning ellipse 0.462 of 3.99
/// (0.459; 1.781 before the unobserved modes were fitted rigid: it turned at two thirds of its
/// speed and sheared), limb 0.244 of 2.86 (0.725, 0.758). Bounds: the measured value plus about
/// 25 %.
#[test]
fn flow_follows_the_whole_motion_of_turning_and_moving_shapes() {
    use fluidymation::quality::TargetKind;
    let bounds = [
        (TargetKind::Translating, 0.12),
        (TargetKind::Growing, 0.065),
        (TargetKind::Rotating, 0.6),
        (TargetKind::Limb, 0.31),
    ];
    check_flow_errors(&bounds, "", |k| (3..20).contains(&k));
}

/// Asserts [`flow_error`] over the flows `which` picks under each target's bound (24 frames).
fn check_flow_errors(
    bounds: &[(fluidymation::quality::TargetKind, f32)],
    what: &str,
    which: impl Fn(usize) -> bool + Copy,
) {
    for &(kind, bound) in bounds {
        let (err, speed) = flow_error(kind, 24, which);
        eprintln!("{kind:?}: mean flow error{what} {err:.3} px of {speed:.2} px/frame");
        assert!(err < bound, "{kind:?}: mean flow error{what} {err:.3} px (bound {bound})");
    }
}

/// The flows of the first three and the last three frames, which the temporal windows reach
/// past the ends of the sequence: the windows read only real frames, never the replicated ends
/// (in which nothing moves), and the last frame's velocity is measured backwards. Measured
/// (24 frames, 512², mean error per pixel over flows 0–2 and 20–22): translating 0.188 px of
/// 3.10 px/frame, growing 0.114 of 2.44, shrinking 0.088 of 2.09, turning ellipse 0.517 of
/// 3.99, limb 0.854 of 5.46; with the replicated ends averaged in, 0.824, 0.652, 0.523, 1.260,
/// 1.117. Bounds: the measured value plus about 25 %.
#[test]
fn flow_keeps_its_speed_at_the_ends_of_the_sequence() {
    use fluidymation::quality::TargetKind;
    let bounds = [
        (TargetKind::Translating, 0.24),
        (TargetKind::Growing, 0.145),
        (TargetKind::Shrinking, 0.11),
        (TargetKind::Rotating, 0.65),
        (TargetKind::Limb, 1.07),
    ];
    check_flow_errors(&bounds, " at the ends", |k| !(3..20).contains(&k));
}

/// Mean flow inside a disc of radius `r` translating by `v` per frame, over the middle frames,
/// as a fraction of `|v|` along `v`. The frame holds the disc in every frame with 20 px to
/// spare (the image edge is not a material boundary).
fn translating_disc_speed(r: f32, v: Vec2) -> f32 {
    let n = 24;
    let start = Vec2::splat(r + 20.0);
    let size = |d: f32| (2.0 * r + 40.0 + d.abs() * n as f32).ceil() as usize;
    let (w, h) = (size(v.x), size(v.y));
    let seq: Vec<_> = (0..n).map(|i| disc(w, h, start + v * i as f32, r)).collect();
    let p = GuideParams::default();
    let g = compute_sequence(&seq, &p).unwrap();
    let (mut along, mut count) = (0f32, 0f32);
    for i in middle(n, &p) {
        let (fw, fh) = g[i].size();
        for y in 0..fh {
            for x in 0..fw {
                if g[i].mask.get(x, y) {
                    along += g[i].flow.get(x, y).dot(v.normalize());
                    count += 1.0;
                }
            }
        }
    }
    along / count / v.length()
}

/// Translating discs keep their speed — less a known shortfall of small, fast ones: a
/// boundary's speed is a distance change over a whole frame, and a curved front that moves far
/// for its radius changes its distance by less than `n·v` (about `(|v|² − (n·v)²)/2R` short at
/// its sides; docs/quality.md, *Where the carrying boils*). The central difference cancels that
/// second-order term; what is left is of third order (a 7-px disc moves half its radius a
/// frame). Measured (mean flow along the motion over the middle frames, as a fraction of the
/// speed): radius 7 px at (3.3, 1.7) px/frame 0.908 (0.865 with the forward difference), at
/// (1.1, 0.6) 0.965 (0.977); radius 60 px at (3.3, 1.7) 0.982 (0.984). Floors 0.87, 0.93 and
/// 0.95 (0.032–0.038 below).
#[test]
fn translating_discs_keep_their_speed() {
    let small_fast = translating_disc_speed(7.0, Vec2::new(3.3, 1.7));
    let small_slow = translating_disc_speed(7.0, Vec2::new(1.1, 0.6));
    let large_fast = translating_disc_speed(60.0, Vec2::new(3.3, 1.7));
    eprintln!(
        "speed along the motion: 7-px disc fast {small_fast:.3}, slow {small_slow:.3}; 60-px disc fast {large_fast:.3}"
    );
    assert!(small_fast > 0.87 && small_slow > 0.93 && large_fast > 0.95, "{small_fast} {small_slow} {large_fast}");
}
