//! Animated values: [`Value::Fixed`] or [`Value::Animated`] keyframes that
//! [`Value::evaluate`] at a (fractional) frame of the layer's local time.
//!
//! Supports linear and cubic-bezier easing per dimension (`i`/`o` handles whose `x`/`y` may be
//! arrays), hold keyframes (`h`), spatial tangents (`to`/`ti`) for positions, and old 4.x
//! keyframes that keep their end value in `e` (the last keyframe then has only `t`).

use super::geom::Bez;
use super::schema;
use glam::Vec2;

/// Values that can be interpolated between keyframes.
pub trait Animatable: Clone {
    /// Interpolates; `t(d)` gives the eased progress of dimension `d`.
    fn lerp(a: &Self, b: &Self, t: &dyn Fn(usize) -> f32) -> Self;
}

impl Animatable for f32 {
    fn lerp(a: &Self, b: &Self, t: &dyn Fn(usize) -> f32) -> Self {
        a + (b - a) * t(0)
    }
}

impl Animatable for Vec2 {
    fn lerp(a: &Self, b: &Self, t: &dyn Fn(usize) -> f32) -> Self {
        Vec2::new(a.x + (b.x - a.x) * t(0), a.y + (b.y - a.y) * t(1))
    }
}

/// A color, straight RGBA in `0..=1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Color(pub [f32; 4]);

impl Animatable for Color {
    fn lerp(a: &Self, b: &Self, t: &dyn Fn(usize) -> f32) -> Self {
        let t = t(0);
        Color(std::array::from_fn(|i| a.0[i] + (b.0[i] - a.0[i]) * t))
    }
}

/// A flat list of numbers (gradient stops).
impl Animatable for Vec<f32> {
    fn lerp(a: &Self, b: &Self, t: &dyn Fn(usize) -> f32) -> Self {
        let t = t(0);
        a.iter().enumerate().map(|(i, &x)| b.get(i).map_or(x, |&y| x + (y - x) * t)).collect()
    }
}

impl Animatable for Bez {
    fn lerp(a: &Self, b: &Self, t: &dyn Fn(usize) -> f32) -> Self {
        a.lerp(b, t(0))
    }
}

/// Easing of one dimension of a keyframe segment: the out handle of the start keyframe and
/// the in handle of the end keyframe, as a CSS-like cubic bezier from (0,0) to (1,1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ease {
    /// Out handle (`o`) of the segment's first keyframe.
    pub out: Vec2,
    /// In handle (`i`) of the segment's first keyframe (the curve's second control point).
    pub inn: Vec2,
}

impl Ease {
    /// The eased progress for linear progress `x` in `0..=1`.
    pub fn apply(&self, x: f32) -> f32 {
        let (p1, p2) = (self.out, self.inn);
        if (p1.x - p1.y).abs() < 1e-6 && (p2.x - p2.y).abs() < 1e-6 {
            return x;
        }
        let x = x.clamp(0.0, 1.0);
        let (x1, x2) = (p1.x.clamp(0.0, 1.0), p2.x.clamp(0.0, 1.0));
        let bez = |a: f32, b: f32, s: f32| {
            let m = 1.0 - s;
            3.0 * m * m * s * a + 3.0 * m * s * s * b + s * s * s
        };
        // Bisection with a Newton start: robust for every handle inside the unit square.
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        let mut s = x;
        for _ in 0..8 {
            let fx = bez(x1, x2, s) - x;
            let m = 1.0 - s;
            let d = 3.0 * m * m * x1 + 6.0 * m * s * (x2 - x1) + 3.0 * s * s * (1.0 - x2);
            if fx.abs() < 1e-6 {
                return bez(p1.y, p2.y, s);
            }
            if d.abs() < 1e-6 {
                break;
            }
            s = (s - fx / d).clamp(0.0, 1.0);
        }
        s = x;
        for _ in 0..40 {
            let fx = bez(x1, x2, s) - x;
            if fx.abs() < 1e-6 {
                break;
            }
            if fx > 0.0 {
                hi = s;
            } else {
                lo = s;
            }
            s = 0.5 * (lo + hi);
        }
        bez(p1.y, p2.y, s)
    }
}

/// One keyframe: the segment from `time` to the next keyframe's time.
#[derive(Clone, Debug)]
pub struct Keyframe<T> {
    /// Frame (layer-local time).
    pub time: f32,
    /// Value at `time`.
    pub start: T,
    /// Value at the next keyframe's time.
    pub end: T,
    /// Easing per dimension (at least one entry; the last one repeats).
    pub ease: Vec<Ease>,
    /// Hold: the value jumps at the next keyframe.
    pub hold: bool,
    /// Spatial tangents (`to`, `ti`) for positions, relative to start and end.
    pub spatial: Option<(Vec2, Vec2)>,
}

/// A property value: fixed, or keyframed.
#[derive(Clone, Debug)]
pub enum Value<T> {
    /// The same at every frame.
    Fixed(T),
    /// Keyframes, sorted by time (at least one).
    Animated(Vec<Keyframe<T>>),
}

impl<T: Animatable> Value<T> {
    /// The value at `frame` (layer-local, fractional).
    pub fn evaluate(&self, frame: f32) -> T {
        match self {
            Value::Fixed(v) => v.clone(),
            Value::Animated(keys) => evaluate_keys(keys, frame),
        }
    }
}

fn evaluate_keys<T: Animatable>(keys: &[Keyframe<T>], frame: f32) -> T {
    let first = &keys[0];
    if keys.len() == 1 || frame.is_nan() || frame <= first.time {
        return first.start.clone();
    }
    // Last keyframe whose time is <= frame.
    let i = keys.partition_point(|k| k.time <= frame).saturating_sub(1);
    let k = &keys[i];
    if i + 1 >= keys.len() {
        return k.start.clone();
    }
    let next = &keys[i + 1];
    let span = next.time - k.time;
    if k.hold || span <= 0.0 {
        return k.start.clone();
    }
    let x = ((frame - k.time) / span).clamp(0.0, 1.0);
    let ease = |d: usize| k.ease[d.min(k.ease.len() - 1)].apply(x);
    T::lerp(&k.start, &k.end, &ease)
}

impl Value<Vec2> {
    /// Evaluates a position, following the spatial bezier (`to`/`ti`) by arc length when present.
    pub fn evaluate_spatial(&self, frame: f32) -> Vec2 {
        let Value::Animated(keys) = self else { return self.evaluate(frame) };
        if keys.len() < 2 || frame.is_nan() || frame <= keys[0].time {
            return self.evaluate(frame);
        }
        let i = keys.partition_point(|k| k.time <= frame).saturating_sub(1);
        let k = &keys[i];
        let Some((to, ti)) = k.spatial else { return self.evaluate(frame) };
        if i + 1 >= keys.len() || k.hold || keys[i + 1].time <= k.time || (to == Vec2::ZERO && ti == Vec2::ZERO) {
            return self.evaluate(frame);
        }
        let x = ((frame - k.time) / (keys[i + 1].time - k.time)).clamp(0.0, 1.0);
        let t = k.ease[0].apply(x);
        let (p0, p3) = (k.start, k.end);
        let (p1, p2) = (p0 + to, p3 + ti);
        point_at_length(p0, p1, p2, p3, t)
    }
}

fn cubic(p0: Vec2, p1: Vec2, p2: Vec2, p3: Vec2, s: f32) -> Vec2 {
    let m = 1.0 - s;
    p0 * (m * m * m) + p1 * (3.0 * m * m * s) + p2 * (3.0 * m * s * s) + p3 * (s * s * s)
}

/// The point at fraction `t` of the arc length of a cubic (may extrapolate slightly for
/// overshooting easing).
fn point_at_length(p0: Vec2, p1: Vec2, p2: Vec2, p3: Vec2, t: f32) -> Vec2 {
    const N: usize = 48;
    let mut lens = [0f32; N + 1];
    let mut prev = p0;
    for (j, len) in lens.iter_mut().enumerate().skip(1) {
        let p = cubic(p0, p1, p2, p3, j as f32 / N as f32);
        *len = (p - prev).length();
        prev = p;
    }
    for j in 1..=N {
        lens[j] += lens[j - 1];
    }
    let total = lens[N];
    if total.is_nan() || total <= 1e-6 {
        return p0 + (p3 - p0) * t;
    }
    if t <= 0.0 {
        return p0 + (cubic(p0, p1, p2, p3, 1.0 / N as f32) - p0) * (t * total / lens[1].max(1e-6));
    }
    if t >= 1.0 {
        let q = cubic(p0, p1, p2, p3, 1.0 - 1.0 / N as f32);
        return p3 + (p3 - q) * ((t - 1.0) * total / (lens[N] - lens[N - 1]).max(1e-6));
    }
    let target = t * total;
    let j = lens.partition_point(|&l| l < target).clamp(1, N);
    let seg = (lens[j] - lens[j - 1]).max(1e-9);
    let s = ((j - 1) as f32 + (target - lens[j - 1]) / seg) / N as f32;
    cubic(p0, p1, p2, p3, s)
}

fn eases(o: &schema::Handle, i: &schema::Handle) -> Vec<Ease> {
    let n = o.x.len().max(o.y.len()).max(i.x.len()).max(i.y.len()).max(1);
    let at =
        |v: &[f32], d: usize, default: f32| v.get(d).or(v.last()).copied().filter(|x| x.is_finite()).unwrap_or(default);
    (0..n)
        .map(|d| Ease {
            out: Vec2::new(at(&o.x, d, 0.0), at(&o.y, d, 0.0)),
            inn: Vec2::new(at(&i.x, d, 1.0), at(&i.y, d, 1.0)),
        })
        .collect()
}

/// A property value that cannot be used (wrong shape, keyframes without a time or out of
/// order); the caller falls back to a default and warns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Malformed;

impl<T: Animatable> Value<T> {
    /// Resolves a property's `k`: keyframes of both layouts become segments from each
    /// keyframe to the next (4.x keep the end value in `e`, 5.x in the next keyframe's `s`).
    pub fn from_schema(k: &schema::Value<T>) -> Result<Value<T>, Malformed> {
        match k {
            schema::Value::Static(v) => Ok(Value::Fixed(v.clone())),
            schema::Value::Animated(keys) => keyframes(keys).map(Value::Animated),
            schema::Value::Malformed => Err(Malformed),
        }
    }
}

fn keyframes<T: Animatable>(keys: &[schema::Keyframe<T>]) -> Result<Vec<Keyframe<T>>, Malformed> {
    let mut out: Vec<Keyframe<T>> = Vec::with_capacity(keys.len());
    for (n, kf) in keys.iter().enumerate() {
        let time = kf.t.filter(|t| t.is_finite()).ok_or(Malformed)?;
        let end = kf.e.clone().flatten();
        let start = match (kf.s.clone(), out.last()) {
            (Some(s), _) => s,
            (None, Some(prev)) => prev.end.clone(),
            (None, None) => end.clone().ok_or(Malformed)?,
        };
        // 5.x: the previous keyframe ends where this one starts (unless it had an `e`).
        if let Some(prev) = out.last_mut()
            && keys[n - 1].e.is_none()
        {
            prev.end = start.clone();
        }
        if out.last().is_some_and(|prev| time < prev.time) {
            return Err(Malformed);
        }
        let spatial = kf.to.zip(kf.ti);
        out.push(Keyframe {
            time,
            end: end.unwrap_or_else(|| start.clone()),
            start,
            ease: eases(&kf.o, &kf.i),
            hold: kf.h,
            spatial,
        });
    }
    if out.is_empty() {
        return Err(Malformed);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn parse_prop<T: Animatable + schema::FromJson>(k: &serde_json::Value) -> Result<Value<T>, Malformed> {
        let k: schema::Value<T> = serde_json::from_value(k.clone()).map_err(|_| Malformed)?;
        Value::from_schema(&k)
    }

    #[test]
    fn linear_and_hold() {
        let k = json!([{"t": 0, "s": [0], "o": {"x": 0, "y": 0}, "i": {"x": 1, "y": 1}}, {"t": 10, "s": [100], "h": 1}, {"t": 20, "s": [50]}]);
        let v: Value<f32> = parse_prop(&k).unwrap();
        assert_eq!(v.evaluate(-5.0), 0.0);
        assert!((v.evaluate(2.5) - 25.0).abs() < 1e-3);
        assert_eq!(v.evaluate(15.0), 100.0);
        assert_eq!(v.evaluate(25.0), 50.0);
    }

    #[test]
    fn old_style_end_values() {
        // Bodymovin 4.x: `e` carries the end value; the last keyframe has only `t`.
        let k = json!([{"t": 0, "s": [10, 20], "e": [30, 60], "i": {"x": [1], "y": [1]}, "o": {"x": [0], "y": [0]}}, {"t": 4}]);
        let v: Value<Vec2> = parse_prop(&k).unwrap();
        assert!((v.evaluate(2.0) - Vec2::new(20.0, 40.0)).length() < 1e-3);
        assert_eq!(v.evaluate(9.0), Vec2::new(30.0, 60.0));
    }

    #[test]
    fn per_dimension_easing() {
        // x linear, y ease-in (slow start): at half time y has moved less than half.
        let k = json!([{"t": 0, "s": [0, 0], "o": {"x": [0, 0.9], "y": [0, 0]}, "i": {"x": [1, 1], "y": [1, 1]}}, {"t": 10, "s": [100, 100]}]);
        let v: Value<Vec2> = parse_prop(&k).unwrap();
        let p = v.evaluate(5.0);
        assert!((p.x - 50.0).abs() < 1e-2, "{p}");
        assert!(p.y < 30.0, "{p}");
        // The ease curve is symmetric: standard "ease" at 0.5 is 0.5.
        let e = Ease { out: Vec2::new(0.42, 0.0), inn: Vec2::new(0.58, 1.0) };
        assert!((e.apply(0.5) - 0.5).abs() < 1e-4);
        assert!(e.apply(0.25) < 0.25);
    }

    #[test]
    fn spatial_tangents_follow_the_curve() {
        // A quarter-circle-like arc from (0,0) to (100,100) bulging through (100,0).
        let k = json!([{"t": 0, "s": [0, 0], "to": [55, 0], "ti": [0, -55], "o": {"x": 0, "y": 0}, "i": {"x": 1, "y": 1}}, {"t": 10, "s": [100, 100]}]);
        let v: Value<Vec2> = parse_prop(&k).unwrap();
        let mid = v.evaluate_spatial(5.0);
        assert!(mid.x > 65.0 && mid.y < 35.0, "{mid}");
        assert!((v.evaluate_spatial(10.0) - Vec2::new(100.0, 100.0)).length() < 1e-3);
    }
}
