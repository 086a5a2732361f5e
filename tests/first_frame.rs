//! The paint does not jump between the first two frames. The first frame starts from a random
//! field; the second, the first with a carried field, used to clean its border band up at
//! once (specks, a rim too wide), so every render began with a visible pop. The first frame is
//! now painted a second time from its own result carried onto itself
//! (`ParamsBuilder::repaint_first`).
//!
//! A still ellipse (radii 150 × 110 px) on a 512² canvas, 4 frames, seed 1, default settings:
//! the mean absolute change per pixel and channel inside the ellipse from frame 1 to 2 against
//! that from frame 2 to 3.

use fluidymation::exemplar::{self, SearchPath};
use fluidymation::img::{Plane, Rgb};
use fluidymation::synth::{self, Params, Source};

const SIDE: usize = 512;

/// The change inside the ellipse `(frame 1 → 2, frame 2 → 3)` with the bundled exemplar
/// `name` and `params`.
fn first_changes(name: &str, params: &Params) -> (f32, f32) {
    let ex = exemplar::find(name, &SearchPath::standard(&[])).unwrap();
    let inside = |x: usize, y: usize| {
        let (u, v) = ((x as f32 - 256.0) / 150.0, (y as f32 - 256.0) / 110.0);
        u * u + v * v <= 1.0
    };
    let ellipse = Plane::from_fn(SIDE, SIDE, |x, y| if inside(x, y) { 1.0 } else { 0.0 });
    let (mut s, stream) = synth::start(|| Source::prepare(&ex, params), params, 3, |_| Ok(ellipse.clone())).unwrap();
    let frames: Vec<Plane<Rgb>> = stream.map(|g| s.step(&g.unwrap()).unwrap().rgb).collect();
    let change = |a: &Plane<Rgb>, b: &Plane<Rgb>| {
        let (mut sum, mut n) = (0.0, 0);
        for y in 0..SIDE {
            for x in 0..SIDE {
                if inside(x, y) {
                    let (p, q) = (a.get(x, y), b.get(x, y));
                    sum += (0..3).map(|k| (p[k] - q[k]).abs()).sum::<f32>();
                    n += 3;
                }
            }
        }
        sum / n as f32
    };
    (change(&frames[0], &frames[1]), change(&frames[1], &frames[2]))
}

/// Measured (change from frame 1 to 2 ÷ from 2 to 3, inside the ellipse): ink-rims 0.00350 ÷
/// 0.00238 = 1.5×, blue-bloom 0.00255 ÷ 0.00190 = 1.3×; with the first frame painted once
/// (`--without repaint-first`) 0.01330 ÷ 0.00306 = 4.3× and 0.00887 ÷ 0.00250 = 3.5× — the rim
/// band of frame 1 rough and wide, of frame 2 clean. Floor: at most 2.5× (the worst measured,
/// 1.5, plus 1; the values before were 3.5 and more). The test also checks that painted once
/// the jump is still there, so that the floor cannot be met by a change that froze the paint.
/// With the finest merge's uniformity (`ParamsBuilder::finest_uniformity`, 2026-12-05):
/// 0.00481 ÷ 0.00341 = 1.4×, 0.00231 ÷ 0.00162 = 1.4×; painted once 3.5× and 3.9×.
/// With the interior's aging (`ParamsBuilder::aging`, 2026-12-05) the still ellipse's paint
/// dries on from frame to frame, a steady change in both runs: 0.00545 ÷ 0.00402 = 1.4×,
/// 0.00436 ÷ 0.00369 = 1.2×; painted once 3.3× and 2.5× (0.01013 ÷ 0.00409) — the jump is
/// still there, but no longer 2.5× the steady change. Floor now 2.0× either way: painted
/// twice at most 2.0× (worst 1.4, margin 0.6), painted once more than 2.0× (least 2.5).
/// With the rim band aged too (`ParamsBuilder::aging` at every depth, 2026-12-05) the rim
/// dries on from frame to frame as well, and the steady change grows in both runs: 0.00797 ÷
/// 0.00662 = 1.2× (ink-rims), 0.00667 ÷ 0.00583 = 1.1× (blue-bloom); painted once 0.01659 ÷
/// 0.00783 = 2.1× and 0.01054 ÷ 0.00627 = 1.7×. Floor now 1.5× either way: painted twice at
/// most 1.5× (worst 1.2, margin 0.3), painted once more than 1.5× (least 1.7, margin 0.2).
#[test]
fn the_paint_does_not_jump_after_the_first_frame() {
    // The change from frame 1 to 2 over that from 2 to 3 that separates a jump from none.
    const FLOOR: f32 = 1.5;
    let mut failures = Vec::new();
    for name in ["ink-rims", "blue-bloom"] {
        let (first, next) = first_changes(name, &Params::builder().seed(1).build().unwrap());
        let (first_once, next_once) =
            first_changes(name, &Params::builder().seed(1).repaint_first(false).build().unwrap());
        println!(
            "{name}: change 1->2 {first:.5}, 2->3 {next:.5} ({:.1}x); painted once {first_once:.5}, {next_once:.5} ({:.1}x)",
            first / next,
            first_once / next_once
        );
        if first > FLOOR * next {
            failures.push(format!("{name}: {first:.5} from frame 1 to 2, {next:.5} from 2 to 3"));
        }
        if first_once <= FLOOR * next_once {
            failures.push(format!("{name} painted once: no jump ({first_once:.5}, {next_once:.5})"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
