//! The generated targets of the quality suite: simple shapes that move the way animated
//! layers move, drawn as anti-aliased coverage.
//!
//! Every target is defined on a 512 × 512 canvas and scaled to the suite's size. Its motion
//! is defined per frame of its default length (48 frames, 300 for [`TargetKind::Long`]): a
//! shorter run plays the beginning of it at the same speed, a longer one slows it down so
//! the shape stays in the frame.

use crate::img::Plane;
use glam::{Mat2, Vec2};
use serde::{Deserialize, Serialize};
use std::f32::consts::TAU;

/// Side of the canvas the targets are defined on, pixels.
pub const CANVAS: f32 = 512.0;

/// One of the suite's targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TargetKind {
    /// An ellipse that does not move.
    Still,
    /// An ellipse that grows (≈ 2 px/frame) and drifts.
    Growing,
    /// An ellipse that shrinks (≈ 2 px/frame) and drifts.
    Shrinking,
    /// An ellipse translating by ≈ 3 px/frame.
    Translating,
    /// An elongated ellipse (2.7 : 1) turning about its center, 2.5°/frame.
    Rotating,
    /// A 14 px wide bar with rounded ends swinging ±25° about its shoulder end like an arm
    /// (one swing forth and back in 48 frames).
    Limb,
    /// A lobed blob that drifts, swells and turns, over 300 frames.
    Long,
}

impl TargetKind {
    /// Every target, in the suite's order.
    pub const ALL: [TargetKind; 7] = [
        TargetKind::Still,
        TargetKind::Growing,
        TargetKind::Shrinking,
        TargetKind::Translating,
        TargetKind::Rotating,
        TargetKind::Limb,
        TargetKind::Long,
    ];

    /// Its name on the command line and in the table.
    pub fn name(self) -> &'static str {
        match self {
            TargetKind::Still => "still",
            TargetKind::Growing => "growing",
            TargetKind::Shrinking => "shrinking",
            TargetKind::Translating => "translating",
            TargetKind::Rotating => "rotating",
            TargetKind::Limb => "limb",
            TargetKind::Long => "long",
        }
    }

    /// The target called `name`.
    pub fn parse(name: &str) -> Option<TargetKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Its length when the suite's length is not given: 300 frames for [`TargetKind::Long`],
    /// 48 for the others.
    pub fn default_frames(self) -> usize {
        if self == TargetKind::Long { 300 } else { 48 }
    }
}

/// A generated target of a given size and length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    kind: TargetKind,
    side: usize,
    frames: usize,
}

impl Target {
    /// `kind` on a `side × side` canvas, `frames` long.
    pub fn new(kind: TargetKind, side: usize, frames: usize) -> Target {
        Target { kind, side: side.max(1), frames: frames.max(1) }
    }

    /// Its kind.
    pub fn kind(&self) -> TargetKind {
        self.kind
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Side of its square frames, pixels.
    pub fn side(&self) -> usize {
        self.side
    }

    /// Time of frame `k` in frames of the default length (see the module documentation).
    fn time(&self, k: usize) -> f32 {
        let d = self.kind.default_frames();
        if self.frames <= d || self.frames < 2 {
            k as f32
        } else {
            k as f32 * (d - 1) as f32 / (self.frames - 1) as f32
        }
    }

    /// Frame `k`'s shape on the 512 canvas, the one description its outline and its pose
    /// are both drawn from.
    fn shape(&self, k: usize) -> Shape {
        let t = self.time(k);
        match self.kind {
            TargetKind::Still => Shape::Ellipse(Vec2::new(256.0, 256.0), 150.0, 115.0, 0.0),
            TargetKind::Growing => {
                Shape::Ellipse(Vec2::new(200.0 + 2.0 * t, 230.0 + 1.0 * t), 70.0 + 2.2 * t, 55.0 + 1.8 * t, 0.0)
            }
            TargetKind::Shrinking => {
                Shape::Ellipse(Vec2::new(300.0 - 1.5 * t, 280.0 - 1.0 * t), 180.0 - 2.2 * t, 150.0 - 1.8 * t, 0.0)
            }
            TargetKind::Translating => Shape::Ellipse(Vec2::new(185.0 + 3.0 * t, 236.0 + 0.8 * t), 110.0, 85.0, 0.0),
            TargetKind::Rotating => Shape::Ellipse(Vec2::new(256.0, 256.0), 190.0, 70.0, 2.5f32.to_radians() * t),
            TargetKind::Limb => Shape::Limb(limb_angle(t)),
            TargetKind::Long => {
                let center = Vec2::new(256.0 + 55.0 * (TAU * t / 300.0).sin(), 256.0 + 40.0 * (TAU * t / 170.0).sin());
                Shape::Blob(center, 105.0 + 25.0 * (TAU * t / 120.0).sin(), 0.9f32.to_radians() * t)
            }
        }
    }

    /// The outline of frame `k` on the 512 canvas.
    fn outline(&self, k: usize) -> Vec<Vec2> {
        match self.shape(k) {
            Shape::Ellipse(center, rx, ry, angle) => ellipse(center, rx, ry, angle),
            Shape::Limb(angle) => capsule(LIMB_SHOULDER, LIMB_SHOULDER + 200.0 * Vec2::from_angle(angle), 7.0),
            Shape::Blob(center, radius, angle) => blob(center, radius, angle),
        }
    }

    /// Where frame `k`'s shape is: the affine map `p = A·u + c` from the shape's own
    /// coordinates `u` to the 512 canvas (the ellipse's unit circle, the limb's shoulder frame,
    /// the blob's unit outline).
    fn pose(&self, k: usize) -> (Mat2, Vec2) {
        let turned = |angle: f32, sx: f32, sy: f32| Mat2::from_angle(angle) * Mat2::from_diagonal(Vec2::new(sx, sy));
        match self.shape(k) {
            Shape::Ellipse(center, rx, ry, angle) => (turned(angle, rx, ry), center),
            Shape::Limb(angle) => (turned(angle, 1.0, 1.0), LIMB_SHOULDER),
            Shape::Blob(center, radius, angle) => (turned(angle, radius, radius), center),
        }
    }

    /// The target's own motion at pixel `(x, y)` from frame `k − 1` to frame `k` (pixels of the
    /// target's size per frame): where the material at `(x, y)` in frame `k − 1` is carried by
    /// the shape's motion — the whole of it, not only the normal part its masks show. `None` at
    /// the first frame.
    pub fn motion(&self, k: usize, x: usize, y: usize) -> Option<Vec2> {
        if k == 0 || k >= self.frames {
            return None;
        }
        let s = self.side as f32 / CANVAS;
        let ((a0, c0), (a1, c1)) = (self.pose(k - 1), self.pose(k));
        let p = Vec2::new(x as f32, y as f32) / s;
        let u = a0.inverse() * (p - c0);
        Some((a1 * u + c1 - p) * s)
    }

    /// Frame `k`'s coverage (`0..=1`, anti-aliased).
    pub fn coverage(&self, k: usize) -> Plane<f32> {
        let s = self.side as f32 / CANVAS;
        let points: Vec<Vec2> = self.outline(k).into_iter().map(|p| p * s).collect();
        fill(&points, self.side)
    }
}

/// The limb's shoulder end, on the 512 canvas.
const LIMB_SHOULDER: Vec2 = Vec2::new(150.0, 256.0);

/// The limb's angle at time `t`: ±25°, one swing forth and back in 48 frames.
fn limb_angle(t: f32) -> f32 {
    25f32.to_radians() * (TAU * t / 48.0).sin()
}

/// One frame's shape on the 512 canvas.
enum Shape {
    /// Centre, radii, angle.
    Ellipse(Vec2, f32, f32, f32),
    /// The limb's angle about [`LIMB_SHOULDER`].
    Limb(f32),
    /// Centre, radius, angle of [`blob`].
    Blob(Vec2, f32, f32),
}

/// Vertices per full turn of a curved outline.
const SEGMENTS: usize = 720;

fn ellipse(center: Vec2, rx: f32, ry: f32, angle: f32) -> Vec<Vec2> {
    let rot = Vec2::from_angle(angle);
    (0..SEGMENTS)
        .map(|i| {
            let a = TAU * i as f32 / SEGMENTS as f32;
            center + rot.rotate(Vec2::new(rx * a.cos(), ry * a.sin()))
        })
        .collect()
}

/// A bar of radius `r` from `a` to `b` with round ends.
fn capsule(a: Vec2, b: Vec2, r: f32) -> Vec<Vec2> {
    let dir = (b - a).normalize_or(Vec2::X);
    let normal = dir.perp();
    let half = SEGMENTS / 2;
    let arc = |center: Vec2, from: Vec2| {
        (0..=half)
            .map(move |i| center + r * from.rotate(Vec2::from_angle(-std::f32::consts::PI * i as f32 / half as f32)))
    };
    // Around the tip from one side to the other, then around the shoulder back.
    arc(b, normal).chain(arc(a, -normal)).collect()
}

/// A blob with three and two lobes turned by `angle`.
fn blob(center: Vec2, radius: f32, angle: f32) -> Vec<Vec2> {
    (0..SEGMENTS)
        .map(|i| {
            let a = TAU * i as f32 / SEGMENTS as f32;
            let u = a - angle;
            let r = radius * (1.0 + 0.16 * (3.0 * u).cos() + 0.07 * (2.0 * u + 1.0).cos());
            center + r * Vec2::from_angle(a)
        })
        .collect()
}

/// Anti-aliased coverage of a closed polygon on a `side × side` canvas.
fn fill(points: &[Vec2], side: usize) -> Plane<f32> {
    let empty = || Plane::filled(side, side, 0.0);
    let Some(mut mask) = tiny_skia::Mask::new(side as u32, side as u32) else { return empty() };
    let mut pb = tiny_skia::PathBuilder::new();
    let Some(first) = points.first() else { return empty() };
    pb.move_to(first.x, first.y);
    for p in &points[1..] {
        pb.line_to(p.x, p.y);
    }
    pb.close();
    let Some(path) = pb.finish() else { return empty() };
    mask.fill_path(&path, tiny_skia::FillRule::Winding, true, tiny_skia::Transform::identity());
    let data = mask.data().iter().map(|&v| v as f32 / 255.0).collect();
    Plane::from_vec(side, side, data).unwrap_or_else(empty)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(c: &Plane<f32>) -> f32 {
        c.data().iter().sum()
    }

    #[test]
    fn shapes_have_their_area_and_move() {
        // The still ellipse: π·150·115 px² on the full canvas, a quarter of it at half size.
        let still = Target::new(TargetKind::Still, 512, 48);
        let a = area(&still.coverage(0));
        assert!((a - std::f32::consts::PI * 150.0 * 115.0).abs() < 60.0, "{a}");
        let half = area(&Target::new(TargetKind::Still, 256, 48).coverage(0));
        assert!((half - a / 4.0).abs() < 30.0, "{half}");
        assert_eq!(still.coverage(0), still.coverage(47));
        // Growing grows, shrinking shrinks, the limb is ~14 px wide and ~214 px long.
        let g = Target::new(TargetKind::Growing, 512, 48);
        assert!(area(&g.coverage(47)) > 3.0 * area(&g.coverage(0)));
        let s = Target::new(TargetKind::Shrinking, 512, 48);
        assert!(area(&s.coverage(47)) < 0.4 * area(&s.coverage(0)));
        let limb = area(&Target::new(TargetKind::Limb, 512, 48).coverage(5));
        let want = 14.0 * 200.0 + std::f32::consts::PI * 49.0;
        assert!((limb - want).abs() < 20.0, "{limb} vs {want}");
        // Anti-aliased: partial coverage on the edge.
        assert!(still.coverage(0).data().iter().any(|&v| v > 0.2 && v < 0.8));
        // Every target stays inside the frame over its default length (and a longer one).
        for kind in TargetKind::ALL {
            for frames in [kind.default_frames(), 2 * kind.default_frames()] {
                let t = Target::new(kind, 128, frames);
                for k in [0, frames / 3, frames / 2, frames - 1] {
                    let c = t.coverage(k);
                    let border: f32 = (0..128).map(|i| c.get(i, 0) + c.get(i, 127) + c.get(0, i) + c.get(127, i)).sum();
                    assert!(border == 0.0 && area(&c) > 100.0, "{kind:?} frame {k} of {frames}");
                }
            }
        }
    }

    #[test]
    fn motion_carries_the_outline_onto_the_next_frame() {
        // The motion is the map from frame k−1's pose to frame k's, for every kind (the pose and
        // the outline are drawn from the same `shape`).
        for kind in TargetKind::ALL {
            let t = Target::new(kind, 256, 48);
            for k in [1, 7, 30] {
                let (a0, c0) = t.pose(k - 1);
                let (a1, c1) = t.pose(k);
                let s = 256.0 / CANVAS;
                for u in [Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)] {
                    let p = (a0 * u + c0) * s;
                    // Sample at the nearest pixel and compare where it goes with the pose map.
                    let (x, y) = (p.x.round(), p.y.round());
                    let m = t.motion(k, x as usize, y as usize).unwrap();
                    let want = ((a1 * (a0.inverse() * (Vec2::new(x, y) / s - c0)) + c1) * s) - Vec2::new(x, y);
                    assert!((m - want).length() < 1e-3, "{kind:?} frame {k}");
                }
            }
            assert!(t.motion(0, 10, 10).is_none());
        }
        // Independently of the pose: points of frame k−1's outline (at the nearest pixel of the
        // full canvas) carried by the motion land on frame k's outline, within the half-pixel
        // diagonal that rounding moved them off it.
        let to_outline = |outline: &[Vec2], q: Vec2| {
            (0..outline.len())
                .map(|i| {
                    let (a, b) = (outline[i], outline[(i + 1) % outline.len()]);
                    let t = ((q - a).dot(b - a) / (b - a).length_squared().max(1e-9)).clamp(0.0, 1.0);
                    (a + t * (b - a) - q).length()
                })
                .fold(f32::INFINITY, f32::min)
        };
        for kind in TargetKind::ALL {
            let t = Target::new(kind, CANVAS as usize, 48);
            for k in [1, 7, 30] {
                let (before, after) = (t.outline(k - 1), t.outline(k));
                for p in before.iter().step_by(before.len() / 16) {
                    let r = p.round();
                    let q = r + t.motion(k, r.x as usize, r.y as usize).unwrap();
                    let d = to_outline(&after, q);
                    assert!(d < 0.75, "{kind:?} frame {k}: {p:?} carried to {q:?}, {d} px off the outline");
                }
            }
        }
        // Known speeds: the translating ellipse moves (3, 0.8) px per frame on the canvas; the
        // still one does not move.
        let tr = Target::new(TargetKind::Translating, 512, 48).motion(5, 100, 300).unwrap();
        assert!((tr - Vec2::new(3.0, 0.8)).length() < 1e-3, "{tr:?}");
        assert!(Target::new(TargetKind::Still, 512, 48).motion(5, 256, 256).unwrap().length() < 1e-6);
        // The limb turns about its shoulder: a point 200 px out moves ~11 px at the start.
        let tip = Target::new(TargetKind::Limb, 512, 48).motion(1, 350, 256).unwrap();
        assert!((tip.length() - 200.0 * limb_angle(1.0)).abs() < 0.2, "{tip:?}");
    }

    #[test]
    fn names_round_trip() {
        for k in TargetKind::ALL {
            assert_eq!(TargetKind::parse(k.name()), Some(k));
        }
        assert_eq!(TargetKind::parse("nope"), None);
    }
}
