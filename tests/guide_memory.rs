//! Peak memory and CPU time of the streaming target path on a long, large sequence (issue 3:
//! 400 frames of 1000×800 must stay far below holding every guide of every frame).
//!
//! Ignored by default (it takes minutes); run with
//! `cargo test --release --test guide_memory -- --ignored --nocapture`, ideally under
//! `/usr/bin/time -v`. It prints the process's peak resident set (`VmHWM`) and CPU time.

use fluidymation::guide::{GuideParams, GuideStream, compute_sequence};
use fluidymation::img::Plane;
use std::time::Instant;

const W: usize = 1000;
const H: usize = 800;

/// A wobbly blob (~15–20 % of the frame) drifting and breathing over the sequence.
fn blob(i: usize) -> Plane<f32> {
    let t = i as f32;
    let (cx, cy) = (300.0 + 1.0 * t, 400.0 + 60.0 * (t * 0.03).sin());
    let breathe = 25.0 * (t * 0.05).sin();
    Plane::from_fn(W, H, |x, y| {
        let (dx, dy) = (x as f32 - cx, y as f32 - cy);
        let a = dy.atan2(dx);
        let r = 200.0 + breathe + 25.0 * (3.0 * a + 0.2 * t).sin() + 12.0 * (5.0 * a - 0.1 * t).cos();
        if dx * dx + dy * dy < r * r { 1.0 } else { 0.0 }
    })
}

fn status(field: &str) -> String {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with(field)).map(|l| l.trim().to_string()))
        .unwrap_or_else(|| format!("{field} unavailable"))
}

/// User + system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat.rsplit(')').next().unwrap_or("").split_whitespace().collect();
    let ticks = |i: usize| fields.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

fn run_stream(n: usize) {
    let params = GuideParams::default();
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let stream = GuideStream::new(n, |i| Ok(blob(i)), &params).unwrap();
    let stored = stream.stored_bytes();
    let (t1, c1) = (Instant::now(), cpu_seconds());
    eprintln!("after the backward pass: {}", status("VmHWM"));
    let mut checksum = 0f64;
    for g in stream {
        let g = g.unwrap();
        checksum += g.ext_neg.data().iter().map(|&v| v as f64).sum::<f64>();
    }
    let (t2, c2) = (Instant::now(), cpu_seconds());
    eprintln!(
        "stream {n} frames of {W}x{H}: backward pass {:.1} s wall / {:.1} s CPU, forward {:.1} s wall / {:.1} s CPU; \
         {:.0} ms wall, {:.0} ms CPU per frame; masks + checkpoints {:.1} MB; checksum {checksum:.3e}",
        (t1 - t0).as_secs_f64(),
        c1 - c0,
        (t2 - t1).as_secs_f64(),
        c2 - c1,
        1000.0 * (t2 - t0).as_secs_f64() / n as f64,
        1000.0 * (c2 - c0) / n as f64,
        stored as f64 / 1e6
    );
    eprintln!("{}", status("VmHWM"));
}

#[test]
#[ignore]
fn stream_400_frames_peak_memory() {
    run_stream(400);
}

#[test]
#[ignore]
fn stream_100_frames() {
    run_stream(100);
}

#[test]
#[ignore]
fn in_memory_only() {
    let frames: Vec<_> = (0..16).map(blob).collect();
    let (t0, c0) = (Instant::now(), cpu_seconds());
    for _ in 0..2 {
        std::hint::black_box(compute_sequence(&frames, &GuideParams::default()).unwrap());
    }
    eprintln!(
        "in memory: {:.0} ms wall, {:.0} ms CPU per frame",
        1000.0 * t0.elapsed().as_secs_f64() / 32.0,
        1000.0 * (cpu_seconds() - c0) / 32.0
    );
}

#[test]
#[ignore]
fn per_frame_cpu_time() {
    let n = 16;
    let frames: Vec<_> = (0..n).map(blob).collect();
    let params = GuideParams::default();
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let g = compute_sequence(&frames, &params).unwrap();
    let (t1, c1) = (Instant::now(), cpu_seconds());
    eprintln!(
        "in memory {n} frames: {:.0} ms wall, {:.0} ms CPU per frame ({} mask px in frame 8)",
        1000.0 * (t1 - t0).as_secs_f64() / n as f64,
        1000.0 * (c1 - c0) / n as f64,
        g[8].mask.count()
    );
    drop(g);
    run_stream(n);
}
