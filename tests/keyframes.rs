//! Painted keyframes (issue 15, part 2): frames painted by the user, carried to every other frame
//! forward and backward, passing from one painting to the next between two keyframes
//! (`synth::keyframes`), and in a render only for the layers a painting paints.

use fluidymation::eval::{self, EvalOptions, Report};
use fluidymation::exemplar::{Exemplar, ExemplarMeta};
use fluidymation::guide::GuideStream;
use fluidymation::img::{Plane, Rgb, Rgba};
use fluidymation::quality::{Target, TargetKind};
use fluidymation::synth::keyframes::{self, KeyedFrame, Keyframe};
use fluidymation::synth::{Params, Synthesizer};

const SIDE: usize = 512;
const FRAMES: usize = 24;
const PAPER: Rgb = [0.953, 0.941, 0.929];

/// Motion of a target from one frame to another, where it is known (`None` where it is not).
type Motion = Box<dyn Fn(usize, usize) -> Option<Plane<Option<glam::Vec2>>> + Sync>;

/// A target: its frames' coverages, and its true motion when known.
struct Seq {
    frames: usize,
    size: (usize, usize),
    cov: Box<dyn Fn(usize) -> Plane<f32> + Sync>,
    motion: Option<Motion>,
    /// The folder of the files drawn from (an SVG sequence reads its frames when drawing),
    /// removed with the target.
    _scratch: Option<tempfile::TempDir>,
}

impl Seq {
    fn coverage(&self, k: usize) -> Plane<f32> {
        (self.cov)(k)
    }

    fn true_motion(&self, from: usize, to: usize) -> Option<Plane<Option<glam::Vec2>>> {
        self.motion.as_ref().and_then(|m| m(from, to))
    }
}

/// A generated target: a shape that moves, at the size users run.
fn target(kind: TargetKind) -> Seq {
    let t = Target::new(kind, SIDE, FRAMES);
    Seq { frames: FRAMES, size: (SIDE, SIDE), cov: Box::new(move |k| t.coverage(k)), motion: None, _scratch: None }
}

/// Layer `layer` of a Lottie animation, frames `range`.
fn animation(path: &str, layer: &str, range: std::ops::Range<usize>) -> Seq {
    let a = std::sync::Arc::new(fluidymation::anim::load(std::path::Path::new(path), &Default::default()).unwrap());
    let r = a.find_region(layer).unwrap();
    let size = (a.width as usize, a.height as usize);
    let (b, start) = (a.clone(), range.start);
    Seq {
        frames: range.len(),
        size,
        cov: Box::new(move |k| a.render(r, start + k).unwrap().coverage()),
        motion: Some(Box::new(move |from, to| b.fill_motion_to(r, start + from, start + to).unwrap())),
        _scratch: None,
    }
}

/// Paintings of frames `keys` of `t`: the engine's own output with an exemplar (ink-rims, whose
/// dark rims and blotches make lost texture easy to see), flattened over the paper — what a
/// painter hands back is paint over the frame, and this is paint of the right shape.
fn paintings(t: &Seq, keys: &[usize]) -> Vec<Keyframe> {
    let ex = fluidymation::exemplar::find("ink-rims", &fluidymation::exemplar::SearchPath::new().with_bundled(true))
        .unwrap();
    let params = Params::builder().seed(3).build().unwrap();
    let (mut synth, stream) = fluidymation::synth::start(
        || fluidymation::synth::Source::prepare(&ex, &params),
        &params,
        t.frames,
        |k| Ok(t.coverage(k)),
    )
    .unwrap();
    let mut out = Vec::new();
    for (k, g) in stream.enumerate() {
        let f = synth.step(&g.unwrap()).unwrap();
        if keys.contains(&k) {
            let painting =
                Plane::from_fn(t.size.0, t.size.1, |x, y| if f.mask.get(x, y) { f.rgb.get(x, y) } else { PAPER });
            out.push(Keyframe { frame: k, painting, mask: None });
        }
    }
    out
}

/// Every frame of `t` painted from `keys`, in order, carried along `t`'s true motion where it
/// is known (as `render` does for a Lottie layer).
fn paint(t: &Seq, keys: &[Keyframe]) -> Vec<KeyedFrame> {
    paint_with(t, keys, true)
}

/// [`paint`], with the motion estimated from the masks unless `true_motion`.
fn paint_with(t: &Seq, keys: &[Keyframe], true_motion: bool) -> Vec<KeyedFrame> {
    let params = Params::builder().seed(1).build().unwrap();
    let mut frames = Vec::new();
    let coverage = |k: usize| Ok(t.coverage(k));
    let motion = |a: usize, b: usize| Ok(t.true_motion(a, b));
    let motion: Option<keyframes::Motion<'_>> = (true_motion && t.motion.is_some()).then_some(&motion);
    let reports = std::sync::Mutex::new(Vec::new());
    let progress = |stage: &str, done: usize, total: usize| {
        reports.lock().unwrap().push((stage.to_string(), done, total));
        true
    };
    keyframes::paint(
        &params,
        t.frames,
        &coverage,
        motion,
        keys,
        &mut |j, f| {
            assert_eq!(j, frames.len(), "frames come in order");
            frames.push(f);
            Ok(())
        },
        "keys",
        &progress,
    )
    .unwrap();
    // Progress: one unit per frame either pass paints, counted up to the announced total.
    let total = keyframes::pass_frames(t.frames, keys.iter().map(|k| k.frame));
    let reports = reports.into_inner().unwrap();
    assert_eq!(reports.len(), total, "one report per frame painted");
    for (i, (stage, done, all)) in reports.iter().enumerate() {
        assert_eq!((stage.as_str(), *done, *all), ("keys", i + 1, total));
    }
    frames
}

/// Every frame painted on its own from keyframe `key` (a fresh synthesizer from its own random
/// field per frame): the reference the issue measures coherence against.
fn independent(t: &Seq, key: &Keyframe) -> Vec<KeyedFrame> {
    let params = Params::builder().seed(1).build().unwrap();
    let source = keyframes::key_source(key, &t.coverage(key.frame), &params).unwrap();
    let stream = GuideStream::new(t.frames, |k| Ok(t.coverage(k)), params.guide()).unwrap();
    stream
        .map(|g| {
            let mut synth = Synthesizer::new(source.clone(), params.clone()).unwrap();
            let f = synth.step(&g.unwrap()).unwrap();
            KeyedFrame { rgb: f.rgb, mask: f.mask }
        })
        .collect()
}

/// The frames measured against the painting of `key` as the exemplar: contrast and rim relative
/// to the painting's own at the same depths, incoherent change, motion agreement.
fn measure(t: &Seq, frames: &[KeyedFrame], key: &Keyframe) -> Report {
    let mask = t.coverage(key.frame);
    let ex = Exemplar {
        dir: None,
        meta: ExemplarMeta::new("painting", PAPER),
        frames: vec![key.painting.clone()],
        masks: vec![mask],
    };
    let rgba: Vec<Plane<Rgba>> = frames
        .iter()
        .map(|f| {
            Plane::from_fn(t.size.0, t.size.1, |x, y| {
                let c = if f.mask.get(x, y) { f.rgb.get(x, y) } else { PAPER };
                [c[0], c[1], c[2], 1.0]
            })
        })
        .collect();
    let masks: Vec<Plane<f32>> = (0..t.frames).map(|k| t.coverage(k)).collect();
    let options = EvalOptions::default().background(PAPER);
    eval::evaluate(&rgba, &ex, &masks, &options).unwrap()
}

/// Motion agreement of `frames` against a motion of the target known to be `v` everywhere (px
/// per frame), instead of the normal motion its masks reveal ([`eval::motion_agreement_with`]).
fn agreement_with_translation(t: &Seq, frames: &[KeyedFrame], v: glam::Vec2) -> f32 {
    agreement_with(t, frames, &|_, _, _| Some(v)).unwrap()
}

/// Motion agreement of `frames` against the target's true motion (`t.motion`: for a Lottie
/// layer, the step of the transforms its fills are drawn with), where it is known; `None` when
/// it is known nowhere.
fn agreement_with_true_motion(t: &Seq, frames: &[KeyedFrame]) -> Option<f32> {
    t.motion.as_ref()?;
    let steps: Vec<Option<Plane<Option<glam::Vec2>>>> = (0..t.frames - 1).map(|k| t.true_motion(k, k + 1)).collect();
    // Frame i's motion is the step from frame i − 1.
    agreement_with(t, frames, &|i, x, y| steps[i - 1].as_ref()?.get(x, y))
}

/// Motion agreement of `frames` against `motion(i, x, y)`, the target's motion from frame i − 1
/// to i ([`eval::motion_agreement_with`]); `None` when there is no point to measure.
fn agreement_with(
    t: &Seq,
    frames: &[KeyedFrame],
    motion: &(dyn Fn(usize, usize, usize) -> Option<glam::Vec2> + Sync),
) -> Option<f32> {
    let lumas: Vec<Plane<f32>> = frames
        .iter()
        .map(|f| {
            Plane::from_fn(t.size.0, t.size.1, |x, y| {
                eval::luma(if f.mask.get(x, y) { f.rgb.get(x, y) } else { PAPER })
            })
        })
        .collect();
    let masks: Vec<Plane<f32>> = (0..t.frames).map(|k| t.coverage(k)).collect();
    let shapes = eval::Shape::sequence(&masks);
    eval::motion_agreement_with(&lumas, &shapes, &EvalOptions::default().motion, motion).value
}

/// PSNR (dB) of `a` against `b` over the pixels of `mask` ([`quality::PSNR_CAP`] where they
/// are the same).
fn psnr(a: &Plane<Rgb>, b: &Plane<Rgb>, mask: &Plane<f32>) -> f32 {
    fluidymation::quality::psnr(a, b, mask).unwrap()
}

/// The lowest contrast ratio over the frames that are not keyframes.
fn lowest_contrast(r: &Report, keys: &[usize]) -> (usize, f32) {
    r.per_frame
        .iter()
        .filter(|f| !keys.contains(&(f.frame - 1)))
        .map(|f| (f.frame, f.contrast_ratio.unwrap_or(0.0)))
        .fold((0, f32::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
}

/// One keyframe in the middle of a translating, and of a growing, shape (512², 24 frames): at
/// the keyframe the output is the painting; forward and backward from it the painting's
/// texture stays and moves with the shape, coherently.
///
/// Measured (seed 1; the painting is ink-rims's own frame 12): translating — every frame's
/// contrast ≥ 0.967 of the painting's (lowest frame 16), incoherent change 0.0048 against
/// 0.0196 painted frame by frame (0.24), motion agreement 0.63; growing — contrast ≥ 0.905
/// (frame 24), incoherent change 0.0051 against 0.0220 (0.23), motion agreement 0.69. The
/// issue's floors: contrast ≥ 0.8 on every frame, coherence ≤ 0.25×, motion agreement ≥ 0.7 —
/// the last not reached on the translating shape against the motion its masks reveal (0.63:
/// they show only the normal part of the translation, so paint that moves exactly with the
/// shape scores well below 1 there), but reached against the whole translation, which this
/// generated target knows: 0.99, against 0.19 for the frames painted on their own
/// ([`eval::motion_agreement_with`]) — and the coherence only just (0.24: ink-rims's calm
/// interior boils little even when every frame is painted on its own).
/// Measured again with the engine of 2026-12-04, before the tone match: translating — lowest
/// contrast 0.945 (frame 16), incoherent change 0.0055 against 0.0251 (0.22), motion 0.63, whole
/// translation 0.99 (alone 0.20); growing — lowest contrast 0.940 (frame 24), 0.0060 against
/// 0.0260 (0.23), motion 0.70. With the tone match (off in `keyframes::paint`, but on in the
/// paintings and the frames painted alone): translating — 0.957 (frame 16), 0.0057 against
/// 0.0300 (0.19), motion 0.64, whole translation 0.99 (alone 0.25); growing — 0.959 (frame 22),
/// 0.0062 against 0.0334 (0.19), motion 0.70. With the finest level's merge weighing Ω and the contrast balance
/// (`ParamsBuilder::finest_uniformity`, 2026-12-05): translating — 0.954 (frame 4), 0.0059 against 0.0288
/// (0.20), motion 0.63, whole translation 0.99 (alone 0.32); growing — 0.936 (frame 24),
/// 0.0061 against 0.0314 (0.19), motion 0.70.
/// Floors: PSNR at the keyframe ≥ 35 dB (it is the painting: the 100 dB cap), contrast ≥ 0.8 (the issue's),
/// coherence ≤ 0.25 (the issue's), motion ≥ 0.58 (the lowest 0.63 less 0.05); against the
/// whole translation ≥ 0.9 (0.99 less 0.09) carried and ≤ 0.5 painted alone (0.19 plus 0.31:
/// the measure must tell the two apart).
#[test]
fn one_keyframe_is_carried_forward_and_backward() {
    for kind in [TargetKind::Translating, TargetKind::Growing] {
        let t = target(kind);
        let keys = paintings(&t, &[11]);
        let out = paint(&t, &keys);
        assert_eq!(out.len(), FRAMES);
        let at_key = psnr(&out[11].rgb, &keys[0].painting, &t.coverage(11));
        assert!(at_key >= 35.0, "{kind:?}: PSNR at the keyframe {at_key}");
        let carried = measure(&t, &out, &keys[0]);
        let alone = measure(&t, &independent(&t, &keys[0]), &keys[0]);
        let (frame, low) = lowest_contrast(&carried, &[11]);
        let (a, b) = (carried.summary.incoherent_change.unwrap(), alone.summary.incoherent_change.unwrap());
        let motion = carried.summary.motion_agreement.unwrap();
        if kind == TargetKind::Translating {
            // The target's own motion, known: (3, 0.8) px a frame on the 512 canvas.
            let v = glam::Vec2::new(3.0, 0.8) * (SIDE as f32 / 512.0);
            let whole = agreement_with_translation(&t, &out, v);
            let alone = agreement_with_translation(&t, &independent(&t, &keys[0]), v);
            println!("{kind:?}: motion agreement with the whole translation {whole:.2} (painted alone {alone:.2})");
            assert!(whole >= 0.9, "{kind:?}: motion agreement with the translation {whole}");
            assert!(alone <= 0.5, "{kind:?}: painted alone, motion agreement with the translation {alone}");
        }
        println!(
            "{kind:?}: lowest contrast {low:.3} (frame {frame}), incoherent change {a:.4} vs {b:.4} \
             alone ({:.2}), motion {motion:.2}",
            a / b
        );
        assert!(low >= 0.8, "{kind:?}: contrast {low} of the painting's at frame {frame}");
        assert!(a <= 0.25 * b, "{kind:?}: incoherent change {a} against {b} painted frame by frame");
        assert!(motion >= 0.58, "{kind:?}: motion agreement {motion}");
    }
}

/// Two keyframes (the first and the last frame of a rotating shape): both are given back, and
/// between them the paint passes from one painting to the other in blobs — no frame is a blend
/// that loses contrast (a cross-fade halves the texture's variance in the middle), and the
/// change stays coherent.
///
/// Measured (seed 1): both keyframes exact; contrast against the first painting ≥ 0.973 on
/// every frame (the middle frames are half the one, half the other); the share of pixels taken
/// from the later painting rises 0.05 → 0.98 over the 22 frames between (first quarter 0.05–
/// 0.13, last 0.93–0.98), never falling; incoherent change 0.0071 (0.0075 before each pass
/// painted only its own blobs). Measured again with the engine of 2026-12-04, before the tone
/// match: contrast ≥ 0.945 (frame 5); the later painting's share 0.05 → 0.98 (first quarter
/// 0.05–0.22, last 0.86–0.98), never falling; incoherent change 0.0076. With the tone match (in
/// the paintings): contrast ≥ 0.968 (frame 5); share 0.05 → 0.99 (first quarter 0.05–0.22,
/// last 0.87–0.99), never falling; incoherent change 0.0080. With the finest level's merge weighing Ω and the contrast balance
/// (`ParamsBuilder::finest_uniformity`, 2026-12-05): contrast ≥ 0.981 (frame 5); share 0.05 → 0.98 (first
/// quarter 0.05–0.22, last 0.87–0.98), never falling; incoherent change 0.0084. Floors: contrast ≥ 0.8 (the
/// issue's); the later painting's share below 0.2 on average in the first quarter of the frames
/// between and above 0.8 in the last, and falling by no more than 0.03 from a frame to the next.
#[test]
fn two_keyframes_pass_from_one_painting_to_the_next() {
    let t = target(TargetKind::Rotating);
    let keys = paintings(&t, &[0, FRAMES - 1]);
    let out = paint(&t, &keys);
    for key in &keys {
        let p = psnr(&out[key.frame].rgb, &key.painting, &t.coverage(key.frame));
        assert!(p >= 35.0, "PSNR {p} at keyframe {}", key.frame + 1);
    }
    let r = measure(&t, &out, &keys[0]);
    let (frame, low) = lowest_contrast(&r, &[0, FRAMES - 1]);
    println!("lowest contrast {low:.3} (frame {frame}), incoherent change {:?}", r.summary.incoherent_change);
    assert!(low >= 0.8, "contrast {low} at frame {frame}");
    // Which painting each pixel comes from: the backward pass alone (painting B) against the
    // forward pass alone (painting A), frame by frame.
    let only_a = paint(&t, &keys[..1]);
    let only_b = paint(&t, &keys[1..]);
    let share_b: Vec<f32> = (1..FRAMES - 1)
        .map(|j| {
            let d = |p: &Rgb, q: &Rgb| (0..3).map(|i| (p[i] - q[i]).abs()).sum::<f32>();
            let (mut from_b, mut n) = (0usize, 0usize);
            let pixels = out[j].rgb.data().iter().zip(only_a[j].rgb.data()).zip(only_b[j].rgb.data());
            for (((o, a), b), m) in pixels.zip(out[j].mask.data()) {
                // Only where the two paintings differ enough to tell which one a pixel shows.
                if *m && d(a, b) > 0.1 {
                    n += 1;
                    from_b += (d(o, b) < d(o, a)) as usize;
                }
            }
            from_b as f32 / n.max(1) as f32
        })
        .collect();
    println!("share of the later painting: {share_b:.2?}");
    let q = share_b.len() / 4;
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    assert!(mean(&share_b[..q]) < 0.2, "{share_b:?}");
    assert!(mean(&share_b[share_b.len() - q..]) > 0.8, "{share_b:?}");
    // Each bit of paint passes once, from the earlier painting to the later.
    assert!(share_b.windows(2).all(|w| w[1] >= w[0] - 0.03), "{share_b:?}");
}

/// A ball that drifts down and to the right, squashes half-way and turns all the while (60°
/// over 24 frames), written as a Lottie file (512 × 512, 24 fps): its motion is in its
/// group's animated position, scale and rotation, as an animator keys it. It moves at most
/// about 5 px a frame, within the reach of the motion measure's block matcher (6 px). A disc
/// that turns looks still to its masks; its transforms know the turn.
fn turning_ball() -> Seq {
    use serde_json::json;
    let linear = json!({"i": {"x": [1], "y": [1]}, "o": {"x": [0], "y": [0]}});
    let key = |t: u32, s: serde_json::Value| {
        let mut k = linear.clone();
        k["t"] = json!(t);
        k["s"] = s;
        k
    };
    let tr = json!({"ty": "tr", "a": {"a": 0, "k": [0, 0]}, "o": {"a": 0, "k": 100},
        "p": {"a": 1, "k": [key(0, json!([200, 210])), key(23, json!([290, 280]))]},
        "s": {"a": 1, "k": [key(0, json!([100, 100])), key(10, json!([100, 100])), key(12, json!([112, 90])),
                            key(14, json!([100, 100])), key(23, json!([100, 100]))]},
        "r": {"a": 1, "k": [key(0, json!([0])), key(23, json!([60]))]}});
    let doc = json!({"v": "5.7.1", "fr": 24, "ip": 0, "op": 24, "w": 512, "h": 512, "layers": [
        {"ty": 4, "nm": "ball", "ind": 1, "ip": 0, "op": 24, "st": 0, "ks": {}, "shapes": [
            {"ty": "gr", "nm": "ball", "it": [
                {"ty": "el", "p": {"a": 0, "k": [0, 0]}, "s": {"a": 0, "k": [150, 150]}},
                {"ty": "fl", "c": {"a": 0, "k": [0.2, 0.3, 0.8, 1]}, "o": {"a": 0, "k": 100}, "r": 1},
                tr]}]}]});
    let dir = tempfile::Builder::new().prefix("fm-keyframes-").tempdir().unwrap();
    let path = dir.path().join("ball.json");
    std::fs::write(&path, doc.to_string()).unwrap();
    let seq = animation(path.to_str().unwrap(), "ball", 0..24);
    Seq { _scratch: Some(dir), ..seq }
}

/// Texture moves with the parts: the [`turning_ball`], painted once in the middle, against
/// the whole motion its transforms give ([`fluidymation::anim::Animation::fill_motion`]), not
/// only the normal part its masks show. The ball keeps its shape in its own coordinates, so
/// its paint is carried along that motion (as `render` does): measured 0.98; carried along the
/// motion its masks show instead, 0.87 — the turn, which a disc's outline does not show, is
/// what that misses (0.98 without the turn); painted frame by frame 0.30 (0.26 with the engine
/// of 2026-12-04, before the tone match; carried 0.985 and 0.873 as before). With the tone match
/// (in the painting): carried 0.984, along the masks' motion 0.874, painted alone 0.338.
/// With the finest level's merge weighing Ω and the contrast balance
/// (`ParamsBuilder::finest_uniformity`, 2026-12-05): carried 0.979, along the masks' motion 0.872, painted
/// alone 0.416.
/// Floors: carried ≥ 0.9 (0.98 less 0.08; the issue's 0.7), at least 0.05 above the masks'
/// carry (0.11 measured), painted alone ≤ 0.55 (0.30 plus 0.25: the measure tells the two
/// apart).
#[test]
fn texture_moves_with_a_turning_ball() {
    let t = turning_ball();
    let keys = paintings(&t, &[11]);
    let carried = agreement_with_true_motion(&t, &paint(&t, &keys)).unwrap();
    let by_masks = agreement_with_true_motion(&t, &paint_with(&t, &keys, false)).unwrap();
    let alone = agreement_with_true_motion(&t, &independent(&t, &keys[0])).unwrap();
    println!(
        "agreement with the ball's true motion: carried {carried:.3} (along the masks' motion {by_masks:.3}), painted alone {alone:.3}"
    );
    assert!(carried >= 0.9, "carried {carried}");
    assert!(carried >= by_masks + 0.05, "carried {carried}, along the masks' motion {by_masks}");
    assert!(alone <= 0.55, "alone {alone}");
}

/// The [`turning_ball`] written as an SVG frame sequence, as an exporter writes one: every
/// frame draws the ball again under its transform of that frame (position, rotation and scale
/// interpolated as the Lottie file keys them).
fn turning_ball_svg() -> Seq {
    let lerp = |keys: &[(f32, f32)], t: f32| {
        let k = keys.windows(2).find(|w| t <= w[1].0).unwrap_or(&keys[keys.len() - 2..]);
        let u = ((t - k[0].0) / (k[1].0 - k[0].0)).clamp(0.0, 1.0);
        k[0].1 + (k[1].1 - k[0].1) * u
    };
    let dir = tempfile::Builder::new().prefix("fm-keyframes-svg-").tempdir().unwrap();
    for i in 0..24 {
        let t = i as f32;
        let (x, y) = (lerp(&[(0.0, 200.0), (23.0, 290.0)], t), lerp(&[(0.0, 210.0), (23.0, 280.0)], t));
        let sx = lerp(&[(0.0, 100.0), (10.0, 100.0), (12.0, 112.0), (14.0, 100.0), (23.0, 100.0)], t) / 100.0;
        let sy = lerp(&[(0.0, 100.0), (10.0, 100.0), (12.0, 90.0), (14.0, 100.0), (23.0, 100.0)], t) / 100.0;
        let r = lerp(&[(0.0, 0.0), (23.0, 60.0)], t);
        let svg = format!(
            r##"<svg xmlns="http://www.w3.org/2000/svg" width="512" height="512" viewBox="0 0 512 512"><g id="ball" transform="translate({x} {y}) rotate({r}) scale({sx} {sy})"><circle cx="0" cy="0" r="75" fill="#334dcc"/></g></svg>"##
        );
        std::fs::write(dir.path().join(format!("ball{i:02}.svg")), svg).unwrap();
    }
    let seq = animation(dir.path().to_str().unwrap(), "ball", 0..24);
    Seq { _scratch: Some(dir), ..seq }
}

/// An SVG sequence gives its elements' motion as the Lottie file gives its transforms': the
/// [`turning_ball_svg`] moves as the [`turning_ball`] does, within 0.05 px wherever both
/// cover a pixel (measured: at most 0.0001 px), and its paint is carried along that motion
/// (measured 0.984, 0.982 before the tone match; floor 0.9 as for the Lottie ball).
#[test]
fn svg_sequences_carry_texture_along_their_elements_motion() {
    let (svg, lottie) = (turning_ball_svg(), turning_ball());
    let mut largest = 0f32;
    for k in [0, 11, 22] {
        let (a, b) = (svg.true_motion(k, k + 1).expect("an SVG motion"), lottie.true_motion(k, k + 1).unwrap());
        for (p, q) in a.data().iter().zip(b.data()) {
            if let (Some(p), Some(q)) = (p, q) {
                largest = largest.max((*p - *q).length());
            }
        }
    }
    let keys = paintings(&svg, &[11]);
    let carried = agreement_with_true_motion(&svg, &paint(&svg, &keys)).unwrap();
    println!("SVG against Lottie motion: at most {largest:.4} px; carried along the SVG motion {carried:.3}");
    assert!(largest < 0.05, "{largest}");
    assert!(carried >= 0.9, "carried {carried}");
}

/// The issue's measures on layers of real animations — the demo's dress, the corpus's bouncing
/// ball and its parenting star (a polygon turning about a moving parent) — with one keyframe in the middle and with two at the ends
/// (48 frames each; the paintings are ink-rims paint of the layer's own shape). Prints a table
/// for the notes (the README's keyframe section has it); asserts the PSNR and contrast floors of
/// the tests above. Run with
/// `cargo test --release --test keyframes animations -- --ignored --nocapture`.
#[test]
#[ignore = "measurement for the notes (about a minute)"]
fn keyframes_on_animations() {
    let demo = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/demo/waving.json");
    let corpus = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/corpus/lottie/");
    let cases = [
        ("demo dress", animation(demo, "dress", 0..48)),
        ("bouncy ball", animation(&format!("{corpus}docs_bouncy_ball.json"), "Layer", 0..48)),
        ("parenting star", animation(&format!("{corpus}docs_parenting.json"), "PolyStar", 0..48)),
    ];
    println!(
        "| layer | keyframes | PSNR at the keys | lowest contrast (frame) | incoherent change (alone) | ratio | motion | true motion (alone) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (name, t) in &cases {
        for keys_at in [vec![23], vec![0, 47]] {
            let keys = paintings(t, &keys_at);
            let out = paint(t, &keys);
            let at_keys = keys
                .iter()
                .map(|k| psnr(&out[k.frame].rgb, &k.painting, &t.coverage(k.frame)))
                .fold(f32::INFINITY, f32::min);
            let r = measure(t, &out, &keys[0]);
            let alone_frames = independent(t, &keys[0]);
            let alone = measure(t, &alone_frames, &keys[0]);
            let (frame, low) = lowest_contrast(&r, &keys_at);
            let (a, b) = (r.summary.incoherent_change.unwrap(), alone.summary.incoherent_change.unwrap());
            let motion = r.summary.motion_agreement.unwrap_or(f32::NAN);
            // Against the layer's whole motion from its transforms, and the same for the
            // frames painted each on their own.
            let true_motion = agreement_with_true_motion(t, &out).unwrap_or(f32::NAN);
            let true_alone = agreement_with_true_motion(t, &alone_frames).unwrap_or(f32::NAN);
            let keys_1: Vec<usize> = keys_at.iter().map(|k| k + 1).collect();
            println!(
                "| {name} | {keys_1:?} | {at_keys:.1} dB | {low:.2} ({frame}) | {a:.4} ({b:.4}) | {:.2} | {motion:.2} | {true_motion:.2} ({true_alone:.2}) |",
                a / b
            );
            assert!(at_keys >= 35.0 && low >= 0.8, "{name} {keys_1:?}");
        }
    }
}
