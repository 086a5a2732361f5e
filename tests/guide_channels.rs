//! The per-frame channels derived from the guides: border channel, segmentation, direction and
//! the pyramid.

use fluidymation::guide::{FrameGuides, GuideParams, Segment, compute_sequence};
use fluidymation::img::Plane;
use glam::Vec2;

/// Hand-made guides: a 6-wide bar of mask moving right at 2 px/frame.
fn bar() -> FrameGuides {
    let (w, h) = (9, 5);
    let mask = Plane::from_fn(w, h, |x, _| (2..8).contains(&x));
    let dist = fluidymation::guide::sdf(&mask);
    let flow = Plane::from_fn(w, h, |x, y| if mask.get(x, y) { Vec2::new(2.0, 0.0) } else { Vec2::ZERO });
    let ext_pos = Plane::from_fn(w, h, |x, _| if mask.get(x, 0) { x as f32 } else { 0.0 });
    let ext_neg = ext_pos.map(|v| 2.0 * v);
    FrameGuides { mask, dist, flow, ext_pos, ext_neg }
}

#[test]
fn border_channel_and_segments() {
    let g = bar();
    // dist across a row: outside −1.5 −0.5 | inside 0.5 1.5 2.5 2.5 1.5 0.5 | outside −0.5.
    assert_eq!(g.dist.row(0), &[-1.5, -0.5, 0.5, 1.5, 2.5, 2.5, 1.5, 0.5, -0.5]);
    let df = g.df(2.0);
    assert_eq!(df.row(2), &[-0.75, -0.25, 0.25, 0.75, 1.0, 1.0, 0.75, 0.25, -0.25]);
    let seg = g.segments(2.0);
    use Segment::*;
    assert_eq!(seg.row(1), &[Outside, Outside, Border, Border, Interior, Interior, Border, Border, Outside]);
    // The segmentation is exactly "in the mask and df = 1".
    for (s, (&d, &m)) in seg.data().iter().zip(df.data().iter().zip(g.mask.data())) {
        assert_eq!(*s == Interior, m && d == 1.0);
        assert_eq!(*s == Outside, !m);
    }
    // A non-positive width makes every mask pixel interior.
    assert!(g.segments(0.0).data().iter().zip(g.mask.data()).all(|(s, &m)| (*s == Interior) == m));
}

#[test]
fn direction_is_atan2_of_the_flow() {
    let mut g = bar();
    g.flow.set(3, 1, Vec2::new(0.0, -1.0));
    g.flow.set(4, 1, Vec2::new(-1.0, 1.0));
    let dir = g.dir();
    assert_eq!(dir.get(2, 0), 0.0);
    assert_eq!(dir.get(3, 1), -std::f32::consts::FRAC_PI_2);
    assert!((dir.get(4, 1) - 3.0 * std::f32::consts::FRAC_PI_4).abs() < 1e-6);
    assert_eq!(dir.get(0, 0), 0.0); // no motion
}

#[test]
fn downsample_keeps_full_resolution_units() {
    let g = bar();
    let d = g.downsample2();
    assert_eq!(d.size(), (5, 3)); // rounds up
    // Pixel (1, 0) covers x = 2, 3 (both inside): mask, averaged extents, flow unchanged.
    assert!(d.mask.get(1, 0));
    assert_eq!(d.flow.get(1, 0), Vec2::new(2.0, 0.0));
    assert_eq!(d.ext_pos.get(1, 0), 2.5);
    assert_eq!(d.ext_neg.get(1, 0), 5.0);
    // Pixel (0, 0) covers x = 0, 1 (outside): no mask, zero flow, distance averaged (not halved).
    assert!(!d.mask.get(0, 0));
    assert_eq!(d.flow.get(0, 0), Vec2::ZERO);
    assert_eq!(d.dist.get(0, 0), -1.0);
    // Pixel (4, ·) covers x = 8 only (clamped): outside.
    assert!(!d.mask.get(4, 1));
    // Half inside (x = 7 inside, 8 outside) counts as inside; the flow averages the inside pixel only.
    let d2 = g.downsample2();
    assert!(d2.mask.get(3, 0) && d2.flow.get(3, 0) == Vec2::new(2.0, 0.0));
}

#[test]
fn pyramid_of_real_guides() {
    let seq: Vec<_> = (0..6)
        .map(|i| {
            Plane::from_fn(101, 67, move |x, y| {
                let (dx, dy) = (x as f32 - 40.0 - 2.0 * i as f32, y as f32 - 33.0);
                if dx * dx + dy * dy < 400.0 { 1.0 } else { 0.0 }
            })
        })
        .collect();
    let g = compute_sequence(&seq, &GuideParams::default().blur_sigma(2.0)).unwrap();
    let p = g[3].pyramid(4);
    assert_eq!(p.len(), 4);
    assert!(p[0] == g[3]);
    assert_eq!(p.iter().map(|l| l.size()).collect::<Vec<_>>(), vec![(101, 67), (51, 34), (26, 17), (13, 9)]);
    // Units stay full-resolution: the deepest interior distance and the motion are not divided by
    // the scale (block averages only round off the peak a little).
    let max_dist = |l: &FrameGuides| l.dist.data().iter().copied().fold(f32::MIN, f32::max);
    let max_flow = |l: &FrameGuides| l.flow.data().iter().map(|f| f.length()).fold(0f32, f32::max);
    for l in &p[1..] {
        assert!(max_dist(l) > 0.7 * max_dist(&p[0]), "{} vs {}", max_dist(l), max_dist(&p[0]));
        assert!(max_flow(l) > 0.8 * max_flow(&p[0]) && max_flow(l) <= max_flow(&p[0]) * 1.001);
    }
    // The mask keeps its area (in full-resolution pixels) within a few percent.
    let area = |l: &FrameGuides, s: f32| l.mask.count() as f32 * s * s;
    assert!((area(&p[2], 4.0) / area(&p[0], 1.0) - 1.0).abs() < 0.1);
    assert!(g[3].pyramid(0).is_empty());
}
