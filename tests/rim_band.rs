//! The border band of a slowly moving shape keeps its paint: it does not gather specks and
//! streaks frame after frame (MERGENNF keeps the carried rim match unless the up-scaled one is
//! four times better, `synth::pyramid`; before, it kept it without comparison).
//!
//! A bar 200 × 40 px with round ends (anti-aliased, 4 × 4 samples a pixel) moves down by 0.5 px
//! a frame for 48 frames on a 512² canvas. In the bar's own coordinates (the motion is known
//! exactly) the change from one frame to the next that the motion does not explain is
//! measured in the band 1–8 px inside its top and bottom edges, over its straight part: the
//! mean over frames 2–8 (the band as first painted) and over the last 20 frames.

use fluidymation::eval::luma;
use fluidymation::exemplar::{self, SearchPath};
use fluidymation::img::{Plane, sample_bilinear};
use fluidymation::synth::{self, Params, Source};

const SIDE: usize = 512;
const FRAMES: usize = 48;
const SPEED: f32 = 0.5;
const RADIUS: f32 = 20.0;

/// The bar's coverage at frame `k` (0-based): its axis from (150, y) to (350, y), y = 230 + 0.5k.
fn bar(k: usize) -> Plane<f32> {
    let (ax, ay) = (150.0f32, 230.0 + SPEED * k as f32);
    Plane::from_fn(SIDE, SIDE, |x, y| {
        let mut n = 0;
        for sy in 0..4 {
            for sx in 0..4 {
                let (px, py) = (x as f32 + (sx as f32 + 0.5) / 4.0, y as f32 + (sy as f32 + 0.5) / 4.0);
                let qx = px.clamp(ax, ax + 200.0);
                n += ((px - qx).powi(2) + (py - ay).powi(2) <= RADIUS * RADIUS) as u32;
            }
        }
        n as f32 / 16.0
    })
}

/// Mean change of the top and bottom bands, `(frames 2–8, last 20 frames)` each, painted with
/// the bundled exemplar `name` (seed 1, default settings).
fn band_change(name: &str) -> [(f32, f32); 2] {
    let ex = exemplar::find(name, &SearchPath::standard(&[])).unwrap();
    let paper = ex.paper();
    let params = Params::builder().seed(1).build().unwrap();
    let (mut s, stream) = synth::start(|| Source::prepare(&ex, &params), &params, FRAMES, |k| Ok(bar(k))).unwrap();
    // The luma of each frame over the paper, in the bar's coordinates: 40 rows (top edge
    // first) by 200 columns, the bar's own pixel centres.
    let mut strips: Vec<Vec<f32>> = Vec::new();
    for (k, g) in stream.enumerate() {
        let out = s.step(&g.unwrap()).unwrap();
        let luma = Plane::from_fn(SIDE, SIDE, |x, y| {
            let c = if out.mask.get(x, y) { out.rgb.get(x, y) } else { paper };
            luma(c)
        });
        let (ax, ay) = (150.0f32, 230.0 + SPEED * k as f32);
        let mut strip = Vec::with_capacity(40 * 200);
        for r in 0..40 {
            for u in 0..200 {
                strip.push(sample_bilinear(&luma, ax + u as f32, ay - RADIUS + r as f32));
            }
        }
        strips.push(strip);
    }
    let change = |k: usize, rows: std::ops::Range<usize>| -> f32 {
        let (mut sum, mut n) = (0.0, 0);
        for r in rows {
            for u in 10..190 {
                sum += (strips[k][r * 200 + u] - strips[k - 1][r * 200 + u]).abs();
                n += 1;
            }
        }
        sum / n as f32
    };
    let mean = |frames: std::ops::Range<usize>, rows: std::ops::Range<usize>| {
        let n = frames.len() as f32;
        frames.map(|k| change(k, rows.clone())).sum::<f32>() / n
    };
    [1..9, 31..39].map(|rows| (mean(2..9, rows.clone()), mean(FRAMES - 20..FRAMES, rows)))
}

/// Measured (early → late band change, top and bottom; the project's luma, `eval::luma`, and
/// the first frame painted twice): blue-swatch 0.0233 → 0.0227 (0.97×) and 0.0173 → 0.0174
/// (1.00×), green-wash 0.0153 → 0.0155 (1.02×) and 0.0283 → 0.0271 (0.96×). When the merge
/// rule was set (Rec. 601 weights, the first frame painted once): 0.97×, 0.94×, 0.98×, 0.96×;
/// with the carried rim kept without comparison (the rule before) they rose: 0.0251 → 0.0314
/// (1.25×), 0.0206 → 0.0246 (1.19×), 0.0194 → 0.0237 (1.22×) and 0.0279 → 0.0325 (1.17×) —
/// dark specks along the trailing edge and streaks along the leading one
/// (`docs/quality-rim-coherence.png`). Floor: the late band changes at most 1.1× the early one
/// (set from the worst then measured, 0.98, plus about 0.1; every value before was above it;
/// today's worst, 1.02, leaves 0.08). With the finest level's merge weighing Ω and the contrast balance
/// (`ParamsBuilder::finest_uniformity`, 2026-12-05): 0.0208 → 0.0205 (0.98×) and 0.0171 →
/// 0.0173 (1.02×), 0.0154 → 0.0167 (1.08×) and 0.0284 → 0.0275 (0.97×): the worst, 1.08,
/// leaves 0.02. Since an inherited match that lands just outside its segment is moved the least
/// distance into it instead of dropped (`ParamsBuilder::segment_snap`, fourth session of
/// 2026-12-06): blue-swatch 0.0195 → 0.0150 (0.77×) and 0.0165 → 0.0165 (1.00×), green-wash
/// 0.0221 → 0.0175 (0.79×) and 0.0548 → 0.0238 (0.43×); blue-swatch's bands change less than
/// without it (0.022 → 0.019 and 0.018 → 0.018, a scratch run). Moved by a whole pixel instead, to the
/// first valid one of the eight around it in a fixed order, blue-swatch's bottom band read
/// 0.0124 → 0.0155 (1.25×): the matches drifted the way that order leans. With a moving
/// shape's paint carried with all of its motion (`ParamsBuilder::full_carry`, fifth session of
/// 2026-12-06): green-wash 0.0221 → 0.0171 (0.78×) and 0.0548 → 0.0231 (0.42×); blue-swatch,
/// a still, unchanged.
#[test]
fn a_slowly_moving_shape_keeps_its_rim_band() {
    let mut failures = Vec::new();
    for name in ["blue-swatch", "green-wash"] {
        for ((early, late), side) in band_change(name).into_iter().zip(["top", "bottom"]) {
            println!("{name}, {side} band: {early:.4} in frames 2-8, {late:.4} in the last 20 ({:.2}x)", late / early);
            if late > 1.1 * early {
                failures.push(format!("{name}, {side} band: {early:.4} -> {late:.4}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
