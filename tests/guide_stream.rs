//! The streaming entry point gives exactly what the in-memory one gives.

use fluidymation::Error;
use fluidymation::guide::{
    FrameGuides, GuideParams, GuideStream, compute_sequence, extent::compute_sequence_with_flow,
};
use fluidymation::img::Plane;
use glam::Vec2;

/// A blob that appears at frame 3, moves and deforms, and is gone from frame 17 on.
fn frame(i: usize) -> Plane<f32> {
    let t = i as f32;
    Plane::from_fn(72, 60, move |x, y| {
        if !(3..17).contains(&i) {
            return 0.0;
        }
        let (dx, dy) = (x as f32 - 20.0 - 1.3 * t, y as f32 - 28.0 - 0.4 * t);
        let r = 9.0 + 0.5 * t + 2.0 * (3.0 * dy.atan2(dx) + 0.3 * t).sin();
        if dx * dx + dy * dy < r * r { 1.0 } else { 0.0 }
    })
}

fn params() -> GuideParams {
    GuideParams::default().blur_sigma(2.0)
}

fn collect(stream: GuideStream) -> Vec<FrameGuides> {
    stream.map(|g| g.unwrap()).collect()
}

#[test]
fn stream_equals_in_memory_for_any_segment_length() {
    let n = 20;
    let frames: Vec<_> = (0..n).map(frame).collect();
    let expected = compute_sequence(&frames, &params()).unwrap();
    assert!(expected[10].ext_pos.data().iter().any(|&v| v > 1.0), "the test sequence must move");
    assert!(expected[10].ext_neg.data().iter().any(|&v| v > 1.0));
    for (seg, keep) in [
        (None, false),
        (Some(1), false),
        (Some(3), false),
        (Some(7), false),
        (Some(40), false),
        (None, true),
        (Some(3), true),
    ] {
        let mut calls = vec![0; n];
        let mut b = GuideStream::builder(&params()).keep_flows(keep);
        if let Some(k) = seg {
            b = b.segment_len(k);
        }
        let stream = b
            .build(n, |i| {
                calls[i] += 1;
                Ok(frame(i))
            })
            .unwrap();
        assert_eq!(stream.frame_count(), n);
        assert!(calls.iter().all(|&c| c == 1), "each mask is read once: {calls:?}");
        let got = collect(stream);
        assert_eq!(got.len(), n);
        for (i, (a, b)) in got.iter().zip(&expected).enumerate() {
            assert!(a == b, "segment length {seg:?}, flows kept {keep}: frame {i} differs");
        }
    }
}

#[test]
fn user_flow_replaces_the_estimate_in_both_entry_points() {
    let n = 12;
    let frames: Vec<_> = (0..n).map(|i| frame(i + 4)).collect();
    let v = Vec2::new(0.5, -0.25);
    let flows = vec![Plane::filled(72, 60, v); n];
    let seq = compute_sequence_with_flow(&frames, &flows, &params()).unwrap();
    // Inside the mask the flow is the given one; ext+ of a pixel covered from frame 0 on grows by |v|.
    let (x, y) = (26, 30);
    for (i, g) in seq.iter().enumerate() {
        assert!(g.mask.get(x, y));
        assert_eq!(g.flow.get(x, y), v);
        assert!((g.ext_pos.get(x, y) - i as f32 * v.length()).abs() < 1e-4);
        assert_eq!(g.flow.get(0, 0), Vec2::ZERO);
    }
    let stream = GuideStream::builder(&params())
        .segment_len(5)
        .flow_source(move |_| Ok(Plane::filled(72, 60, v)))
        .build(n, |i| Ok(frame(i + 4)))
        .unwrap();
    assert!(collect(stream) == seq);
}

#[test]
fn errors_are_reported_not_panicked() {
    // A frame of another size.
    let err = GuideStream::new(5, |i| Ok(if i == 2 { Plane::new(10, 10) } else { frame(5) }), &params()).err();
    assert!(matches!(err, Some(Error::InvalidParam { .. })), "{err:?}");
    let err = compute_sequence(&[frame(5), Plane::new(3, 3)], &params()).unwrap_err();
    assert!(err.to_string().contains("3x3 at frame 1"), "{err}");
    // A failing source.
    let err = GuideStream::new(5, |_| Err(Error::Cancelled), &params()).err();
    assert!(matches!(err, Some(Error::Cancelled)));
    // Bad parameters.
    let bad = GuideParams::default().mask_threshold(0.0);
    assert!(compute_sequence(&[frame(5)], &bad).is_err());
    let bad = GuideParams::default().time_blur_sigma(f32::NAN);
    assert!(GuideStream::new(1, |_| Ok(frame(5)), &bad).is_err());
    // Cancellation through the progress callback.
    let stop = |_: &str, done: usize, _: usize| done < 3;
    let err = GuideStream::builder(&params()).progress(&stop).build(8, |i| Ok(frame(i))).err();
    assert!(matches!(err, Some(Error::Cancelled)));
    // Wrong number of user flows.
    assert!(compute_sequence_with_flow(&[frame(5)], &[], &params()).is_err());
    // Nothing at all.
    assert_eq!(GuideStream::new(0, |_| Ok(frame(5)), &params()).unwrap().count(), 0);
    assert!(compute_sequence(&[], &params()).unwrap().is_empty());
}

#[test]
fn empty_frames_get_sane_guides() {
    let g = compute_sequence(&(0..6).map(frame).collect::<Vec<_>>(), &params()).unwrap();
    let empty = &g[0];
    assert_eq!(empty.mask.count(), 0);
    let d = empty.dist.get(0, 0);
    assert!(d.is_finite() && d < -90.0, "{d}");
    assert!(empty.flow.data().iter().all(|f| *f == Vec2::ZERO));
    // The first frame with paint: nothing has moved yet.
    assert!(g[3].mask.count() > 0);
    assert!(g[3].ext_pos.data().iter().all(|&e| e == 0.0));
    assert!(g.iter().all(|f| f.flow.data().iter().all(|v| v.is_finite())));
}

#[test]
fn flow_estimate_alone_matches_the_full_guides() {
    let frames: Vec<_> = (0..14).map(frame).collect();
    let g = compute_sequence(&frames, &params()).unwrap();
    let masks: Vec<_> = g.iter().map(|f| f.mask.clone()).collect();
    let flows = fluidymation::guide::flow::estimate_sequence(&masks, &params()).unwrap();
    assert_eq!(flows.len(), g.len());
    for (f, gi) in flows.iter().zip(&g) {
        assert!(*f == gi.flow);
    }
}

#[test]
fn kept_flows_are_not_asked_for_again() {
    use std::sync::{Arc, Mutex};
    let n = 9;
    for (keep, expected) in [(false, 2 * n), (true, n)] {
        let calls = Arc::new(Mutex::new(0));
        let c = calls.clone();
        let stream = GuideStream::builder(&params())
            .segment_len(4)
            .keep_flows(keep)
            .flow_source(move |_| {
                *c.lock().unwrap() += 1;
                Ok(Plane::filled(72, 60, Vec2::new(0.5, 0.0)))
            })
            .build(n, |i| Ok(frame(i + 4)))
            .unwrap();
        assert_eq!(collect(stream).len(), n);
        assert_eq!(*calls.lock().unwrap(), expected, "flows kept: {keep}");
    }
}
