//! Bezier paths in Lottie's own form (vertices with relative in/out tangents) and the
//! geometry operations on them: primitives (rect, ellipse, polystar), trimming by arc length,
//! rounded corners, affine transforms and conversion to tiny-skia paths.

use glam::{Affine2, Vec2};

/// Kappa for approximating a quarter circle with a cubic.
pub const KAPPA: f32 = 0.552_284_8;

/// One Lottie bezier path: vertices `v`, in-tangents `i` and out-tangents `o` relative to
/// their vertex; closed paths have a segment from the last vertex back to the first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bez {
    /// True when the path is closed.
    pub closed: bool,
    /// Vertices.
    pub v: Vec<Vec2>,
    /// In-tangents, relative to their vertex.
    pub i: Vec<Vec2>,
    /// Out-tangents, relative to their vertex.
    pub o: Vec<Vec2>,
}

/// A cubic segment: start, two control points, end.
pub type Cubic = [Vec2; 4];

impl Bez {
    /// Interpolates vertex by vertex (paths with different vertex counts do not morph).
    pub fn lerp(&self, other: &Bez, t: f32) -> Bez {
        if self.v.len() != other.v.len() {
            return if t < 1.0 { self.clone() } else { other.clone() };
        }
        let l = |a: &[Vec2], b: &[Vec2]| a.iter().zip(b).map(|(x, y)| x.lerp(*y, t)).collect();
        Bez { closed: self.closed, v: l(&self.v, &other.v), i: l(&self.i, &other.i), o: l(&self.o, &other.o) }
    }

    /// Number of cubic segments.
    pub fn segment_count(&self) -> usize {
        match self.v.len() {
            0 => 0,
            n if self.closed => n,
            n => n - 1,
        }
    }

    /// Segment `k` as absolute cubic control points.
    pub fn segment(&self, k: usize) -> Cubic {
        let n = self.v.len();
        let (a, b) = (k % n, (k + 1) % n);
        if self.o[a] == Vec2::ZERO && self.i[b] == Vec2::ZERO {
            // A straight segment, parametrized uniformly (control points at the thirds) so
            // that arc length and parameter agree when trimming.
            let d = (self.v[b] - self.v[a]) / 3.0;
            return [self.v[a], self.v[a] + d, self.v[b] - d, self.v[b]];
        }
        [self.v[a], self.v[a] + self.o[a], self.v[b] + self.i[b], self.v[b]]
    }

    /// Builds an open path from consecutive cubics.
    pub fn from_cubics(cubics: &[Cubic], closed: bool) -> Bez {
        let mut b = Bez { closed, ..Default::default() };
        for (k, c) in cubics.iter().enumerate() {
            if k == 0 {
                b.v.push(c[0]);
                b.i.push(Vec2::ZERO);
                b.o.push(c[1] - c[0]);
            } else if let Some(o) = b.o.last_mut() {
                *o = c[1] - c[0];
            }
            if closed && k + 1 == cubics.len() {
                b.i[0] = c[2] - c[3];
            } else {
                b.v.push(c[3]);
                b.i.push(c[2] - c[3]);
                b.o.push(Vec2::ZERO);
            }
        }
        b
    }

    /// Applies an affine transform.
    pub fn transformed(&self, m: &Affine2) -> Bez {
        Bez {
            closed: self.closed,
            v: self.v.iter().map(|&p| m.transform_point2(p)).collect(),
            i: self.i.iter().map(|&p| m.transform_vector2(p)).collect(),
            o: self.o.iter().map(|&p| m.transform_vector2(p)).collect(),
        }
    }

    /// Reverses the direction.
    pub fn reversed(&self) -> Bez {
        let mut b = Bez {
            closed: self.closed,
            v: self.v.iter().rev().copied().collect(),
            i: self.o.iter().rev().copied().collect(),
            o: self.i.iter().rev().copied().collect(),
        };
        if self.closed && !b.v.is_empty() {
            // Keep the first vertex first.
            b.v.rotate_right(1);
            b.i.rotate_right(1);
            b.o.rotate_right(1);
        }
        b
    }

    /// Appends this path to a tiny-skia path builder.
    pub fn append_to(&self, pb: &mut tiny_skia::PathBuilder) {
        if self.v.is_empty() || !self.v.iter().all(|p| p.is_finite()) {
            return;
        }
        pb.move_to(self.v[0].x, self.v[0].y);
        for k in 0..self.segment_count() {
            let [_, c1, c2, p] = self.segment(k);
            let n = self.v.len();
            let third = (p - self.v[k % n]) / 3.0;
            if self.o[k % n] == Vec2::ZERO && self.i[(k + 1) % n] == Vec2::ZERO
                || (self.o[k % n] - third).length_squared() < 1e-10
                    && (self.i[(k + 1) % n] + third).length_squared() < 1e-10
            {
                pb.line_to(p.x, p.y);
            } else {
                pb.cubic_to(c1.x, c1.y, c2.x, c2.y, p.x, p.y);
            }
        }
        if self.closed {
            pb.close();
        }
    }
}

/// Builds a tiny-skia path from several Lottie paths; `None` when empty or degenerate.
pub fn to_skia_path(paths: &[Bez]) -> Option<tiny_skia::Path> {
    let mut pb = tiny_skia::PathBuilder::new();
    for p in paths {
        p.append_to(&mut pb);
    }
    pb.finish()
}

/// Rectangle `rc` centered at `p` with size `s` and corner radius `r`, starting at the top
/// right corner and running clockwise (reversed when `reverse`).
pub fn rect(p: Vec2, s: Vec2, r: f32, reverse: bool) -> Bez {
    let (hw, hh) = (s.x.abs() / 2.0, s.y.abs() / 2.0);
    let r = r.max(0.0).min(hw).min(hh);
    let (l, t, rt, b) = (p.x - hw, p.y - hh, p.x + hw, p.y + hh);
    let bez = if r <= 0.0 {
        let v = vec![Vec2::new(rt, t), Vec2::new(rt, b), Vec2::new(l, b), Vec2::new(l, t)];
        Bez { closed: true, i: vec![Vec2::ZERO; 4], o: vec![Vec2::ZERO; 4], v }
    } else {
        let k = r * KAPPA;
        let v = vec![
            Vec2::new(rt, t + r),
            Vec2::new(rt, b - r),
            Vec2::new(rt - r, b),
            Vec2::new(l + r, b),
            Vec2::new(l, b - r),
            Vec2::new(l, t + r),
            Vec2::new(l + r, t),
            Vec2::new(rt - r, t),
        ];
        let z = Vec2::ZERO;
        let i = vec![Vec2::new(0.0, -k), z, Vec2::new(k, 0.0), z, Vec2::new(0.0, k), z, Vec2::new(-k, 0.0), z];
        let o = vec![z, Vec2::new(0.0, k), z, Vec2::new(-k, 0.0), z, Vec2::new(0.0, -k), z, Vec2::new(k, 0.0)];
        Bez { closed: true, v, i, o }
    };
    if reverse { bez.reversed() } else { bez }
}

/// Ellipse `el` centered at `p` with size `s`, starting at the top, clockwise.
pub fn ellipse(p: Vec2, s: Vec2, reverse: bool) -> Bez {
    let (rx, ry) = (s.x / 2.0, s.y / 2.0);
    let (kx, ky) = (rx * KAPPA, ry * KAPPA);
    let v = vec![p + Vec2::new(0.0, -ry), p + Vec2::new(rx, 0.0), p + Vec2::new(0.0, ry), p + Vec2::new(-rx, 0.0)];
    let i = vec![Vec2::new(-kx, 0.0), Vec2::new(0.0, -ky), Vec2::new(kx, 0.0), Vec2::new(0.0, ky)];
    let o = vec![Vec2::new(kx, 0.0), Vec2::new(0.0, ky), Vec2::new(-kx, 0.0), Vec2::new(0.0, -ky)];
    let b = Bez { closed: true, v, i, o };
    if reverse { b.reversed() } else { b }
}

/// Parameters of a polystar `sr`.
#[derive(Clone, Copy, Debug)]
pub struct Star {
    /// Center.
    pub center: Vec2,
    /// Number of points (star) or corners (polygon).
    pub points: f32,
    /// Rotation in degrees.
    pub rotation: f32,
    /// Outer radius.
    pub outer_radius: f32,
    /// Outer roundness in percent.
    pub outer_roundness: f32,
    /// Inner radius (star only).
    pub inner_radius: f32,
    /// Inner roundness in percent (star only).
    pub inner_roundness: f32,
    /// True for a star, false for a polygon.
    pub star: bool,
    /// Counter-clockwise.
    pub reverse: bool,
}

/// Largest number of polystar points drawn.
pub const MAX_STAR_POINTS: f32 = 1000.0;

/// The polystar path: first point straight up (before rotation), clockwise.
pub fn polystar(s: &Star) -> Bez {
    let pts = s.points.floor().clamp(0.0, MAX_STAR_POINTS) as usize;
    let n = if s.star { pts * 2 } else { pts };
    let mut b = Bez { closed: true, ..Default::default() };
    if n == 0 {
        return b;
    }
    let step = std::f32::consts::TAU / n as f32;
    let dir = if s.reverse { -1.0 } else { 1.0 };
    let mut angle = -std::f32::consts::FRAC_PI_2 + s.rotation.to_radians();
    for k in 0..n {
        let outer = !s.star || k % 2 == 0;
        let (rad, round) =
            if outer { (s.outer_radius, s.outer_roundness) } else { (s.inner_radius, s.inner_roundness) };
        // Tangent length: the roundness share of a quarter of the slice of circumference.
        let perim = std::f32::consts::TAU * rad / (4.0 * pts as f32);
        let p = Vec2::new(rad * angle.cos(), rad * angle.sin());
        let len = p.length();
        let tangent = if len > 0.0 { Vec2::new(p.y, -p.x) / len } else { Vec2::ZERO };
        let t = tangent * (perim * round / 100.0 * dir);
        b.v.push(s.center + p);
        b.i.push(t);
        b.o.push(-t);
        angle += step * dir;
    }
    b
}

// ---------------------------------------------------------------------------------------
// Arc length, trimming

fn cubic_point(c: &Cubic, s: f32) -> Vec2 {
    let m = 1.0 - s;
    c[0] * (m * m * m) + c[1] * (3.0 * m * m * s) + c[2] * (3.0 * m * s * s) + c[3] * (s * s * s)
}

const LEN_STEPS: usize = 16;

/// Cumulative chord lengths at `LEN_STEPS` parameter steps of a cubic.
fn length_table(c: &Cubic) -> [f32; LEN_STEPS + 1] {
    let mut t = [0f32; LEN_STEPS + 1];
    let third = (c[3] - c[0]) / 3.0;
    if (c[1] - c[0] - third).length_squared() < 1e-12 && (c[3] - c[2] - third).length_squared() < 1e-12 {
        let l = (c[3] - c[0]).length();
        for (j, x) in t.iter_mut().enumerate() {
            *x = l * j as f32 / LEN_STEPS as f32;
        }
        return t;
    }
    let mut prev = c[0];
    for j in 1..=LEN_STEPS {
        let p = cubic_point(c, j as f32 / LEN_STEPS as f32);
        t[j] = t[j - 1] + (p - prev).length();
        prev = p;
    }
    t
}

/// Parameter at arc length `l` along a cubic with the given table.
fn param_at(table: &[f32; LEN_STEPS + 1], l: f32) -> f32 {
    let total = table[LEN_STEPS];
    if total <= 0.0 || l <= 0.0 {
        return 0.0;
    }
    if l >= total {
        return 1.0;
    }
    let j = table.partition_point(|&x| x < l).clamp(1, LEN_STEPS);
    let seg = (table[j] - table[j - 1]).max(1e-12);
    ((j - 1) as f32 + (l - table[j - 1]) / seg) / LEN_STEPS as f32
}

/// The part of a cubic between parameters `t0 <= t1`.
pub fn sub_cubic(c: &Cubic, t0: f32, t1: f32) -> Cubic {
    fn split_right(c: &Cubic, t: f32) -> Cubic {
        // The part from t to 1.
        let ab = c[0].lerp(c[1], t);
        let bc = c[1].lerp(c[2], t);
        let cd = c[2].lerp(c[3], t);
        let abc = ab.lerp(bc, t);
        let bcd = bc.lerp(cd, t);
        let p = abc.lerp(bcd, t);
        [p, bcd, cd, c[3]]
    }
    fn split_left(c: &Cubic, t: f32) -> Cubic {
        let ab = c[0].lerp(c[1], t);
        let bc = c[1].lerp(c[2], t);
        let cd = c[2].lerp(c[3], t);
        let abc = ab.lerp(bc, t);
        let bcd = bc.lerp(cd, t);
        let p = abc.lerp(bcd, t);
        [c[0], ab, abc, p]
    }
    let right = if t0 > 0.0 { split_right(c, t0) } else { *c };
    if t1 >= 1.0 {
        return right;
    }
    let t = if t0 < 1.0 { ((t1 - t0) / (1.0 - t0)).clamp(0.0, 1.0) } else { 1.0 };
    split_left(&right, t)
}

/// A path measured for trimming.
pub struct Measured {
    cubics: Vec<Cubic>,
    tables: Vec<[f32; LEN_STEPS + 1]>,
    /// Cumulative length at the start of each segment, plus the total at the end.
    starts: Vec<f32>,
    closed: bool,
}

impl Measured {
    /// Measures a path.
    pub fn new(b: &Bez) -> Measured {
        let cubics: Vec<Cubic> = (0..b.segment_count()).map(|k| b.segment(k)).collect();
        let tables: Vec<_> = cubics.iter().map(length_table).collect();
        let mut starts = Vec::with_capacity(cubics.len() + 1);
        let mut acc = 0.0;
        starts.push(0.0);
        for t in &tables {
            acc += t[LEN_STEPS];
            starts.push(acc);
        }
        Measured { cubics, tables, starts, closed: b.closed }
    }

    /// Total length.
    pub fn length(&self) -> f32 {
        self.starts.last().copied().unwrap_or(0.0)
    }

    /// The piece between arc lengths `a < b` (both within `0..=length`), as an open path.
    pub fn extract(&self, a: f32, b: f32) -> Option<Bez> {
        if a.is_nan() || b.is_nan() || b <= a || self.cubics.is_empty() {
            return None;
        }
        let mut out: Vec<Cubic> = Vec::new();
        for (k, c) in self.cubics.iter().enumerate() {
            let (s0, s1) = (self.starts[k], self.starts[k + 1]);
            if s1 < a || s0 > b || s1 <= s0 && !(a <= s0 && s0 <= b) {
                continue;
            }
            let t0 = if a > s0 { param_at(&self.tables[k], a - s0) } else { 0.0 };
            let t1 = if b < s1 { param_at(&self.tables[k], b - s0) } else { 1.0 };
            if t1 > t0 || (t0 == 0.0 && t1 == 1.0) {
                out.push(sub_cubic(c, t0, t1));
            }
        }
        if out.is_empty() { None } else { Some(Bez::from_cubics(&out, false)) }
    }

    /// The piece from `a` to `b` where `b` may exceed the length: a closed path wraps around
    /// (one continuous piece), an open one gives two pieces.
    pub fn extract_wrapping(&self, a: f32, b: f32, out: &mut Vec<Bez>) {
        let len = self.length();
        if b <= len {
            out.extend(self.extract(a, b));
            return;
        }
        let first = self.extract(a, len);
        let second = self.extract(0.0, b - len);
        match (first, second) {
            (Some(mut f), Some(s)) if self.closed => {
                // Join: drop the duplicated vertex where the path closes.
                if let (Some(last_o), Some(&s_o0)) = (f.o.last_mut(), s.o.first()) {
                    *last_o = s_o0;
                }
                f.v.extend(s.v.iter().skip(1));
                f.i.extend(s.i.iter().skip(1));
                f.o.extend(s.o.iter().skip(1));
                let n = f.v.len();
                if let (Some(&last_i), true) = (s.i.first(), n > 0) {
                    // The join vertex keeps the first piece's in-tangent.
                    let _ = last_i;
                }
                out.push(f);
            }
            (f, s) => {
                out.extend(f);
                out.extend(s);
            }
        }
    }
}

/// The ranges of a trim, as fractions: start `s` and end `e` in `0..=1`, offset `o` in turns.
/// Returns `None` for "everything", else (start, end) with start in `0..1` and end possibly
/// above 1 (wrapping); an empty range gives `Some((x, x))`.
pub fn trim_range(s: f32, e: f32, o: f32) -> Option<(f32, f32)> {
    let (s, e) = (s.clamp(0.0, 1.0), e.clamp(0.0, 1.0));
    let (s, e) = if s > e { (e, s) } else { (s, e) };
    if e - s >= 1.0 - 1e-6 {
        return None;
    }
    let o = if o.is_finite() { o } else { 0.0 };
    let start = (s + o).rem_euclid(1.0);
    Some((start, start + (e - s)))
}

/// Trims each path on its own (`simultaneously`) or all as one sequence (`individually`).
pub fn trim(paths: &[Bez], s: f32, e: f32, o: f32, sequential: bool) -> Vec<Bez> {
    let Some((a, b)) = trim_range(s, e, o) else { return paths.to_vec() };
    let mut out = Vec::new();
    if b <= a {
        return out;
    }
    if !sequential {
        for p in paths {
            let m = Measured::new(p);
            let len = m.length();
            m.extract_wrapping(a * len, b * len, &mut out);
        }
        return out;
    }
    let measured: Vec<Measured> = paths.iter().map(Measured::new).collect();
    let total: f32 = measured.iter().map(|m| m.length()).sum();
    let mut ranges = vec![(a * total, b.min(1.0) * total)];
    if b > 1.0 {
        ranges.push((0.0, (b - 1.0) * total));
    }
    // With wrapping on one closed path, keep it in one piece.
    if measured.len() == 1 {
        measured[0].extract_wrapping(a * total, b * total, &mut out);
        return out;
    }
    let mut acc = 0.0;
    for m in &measured {
        let len = m.length();
        for &(ra, rb) in &ranges {
            let (x, y) = ((ra - acc).max(0.0), (rb - acc).min(len));
            if y > x {
                out.extend(m.extract(x, y));
            }
        }
        acc += len;
    }
    out
}

/// Sequential trim over all `paths` as one sequence; returns, for each input path, the
/// pieces that remain of it (so that callers can give them back to their owners).
pub fn trim_sequential_per_path(paths: &[Bez], s: f32, e: f32, o: f32) -> Vec<Vec<Bez>> {
    let Some((a, b)) = trim_range(s, e, o) else { return paths.iter().map(|p| vec![p.clone()]).collect() };
    if b <= a {
        return paths.iter().map(|_| Vec::new()).collect();
    }
    let measured: Vec<Measured> = paths.iter().map(Measured::new).collect();
    let total: f32 = measured.iter().map(|m| m.length()).sum();
    if measured.len() == 1 {
        let mut out = Vec::new();
        measured[0].extract_wrapping(a * total, b * total, &mut out);
        return vec![out];
    }
    let mut ranges = vec![(a * total, b.min(1.0) * total)];
    if b > 1.0 {
        ranges.push((0.0, (b - 1.0) * total));
    }
    let mut acc = 0.0;
    let mut result = Vec::with_capacity(paths.len());
    for m in &measured {
        let len = m.length();
        let mut pieces = Vec::new();
        for &(ra, rb) in &ranges {
            let (x, y) = ((ra - acc).max(0.0), (rb - acc).min(len));
            if y > x {
                pieces.extend(m.extract(x, y));
            }
        }
        result.push(pieces);
        acc += len;
    }
    result
}

/// Rounds sharp corners (vertices without tangents) with radius `r`.
pub fn round_corners(p: &Bez, r: f32) -> Bez {
    let n = p.v.len();
    if r <= 0.0 || n < 2 || !r.is_finite() {
        return p.clone();
    }
    let mut out = Bez { closed: p.closed, ..Default::default() };
    for k in 0..n {
        let v = p.v[k];
        let sharp = p.i[k] == Vec2::ZERO && p.o[k] == Vec2::ZERO;
        let endpoint = !p.closed && (k == 0 || k == n - 1);
        if !sharp || endpoint {
            out.v.push(v);
            out.i.push(p.i[k]);
            out.o.push(p.o[k]);
            continue;
        }
        let prev = p.v[(k + n - 1) % n];
        let next = p.v[(k + 1) % n];
        let (dp, dn) = (prev - v, next - v);
        let (lp, ln) = (dp.length(), dn.length());
        if lp <= 0.0 || ln <= 0.0 {
            out.v.push(v);
            out.i.push(Vec2::ZERO);
            out.o.push(Vec2::ZERO);
            continue;
        }
        let rp = r.min(lp / 2.0);
        let rn = r.min(ln / 2.0);
        let a = v + dp / lp * rp;
        let b = v + dn / ln * rn;
        let k1 = 1.0 - KAPPA;
        out.v.push(a);
        out.i.push(Vec2::ZERO);
        out.o.push((v - a) * (1.0 - k1));
        out.v.push(b);
        out.i.push((v - b) * (1.0 - k1));
        out.o.push(Vec2::ZERO);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rect_length_and_trim() {
        let r = rect(Vec2::new(50.0, 50.0), Vec2::new(40.0, 20.0), 0.0, false);
        let m = Measured::new(&r);
        assert!((m.length() - 120.0).abs() < 1e-3);
        // Half of the outline starting at the top-right corner: right side + bottom side.
        let t = trim(std::slice::from_ref(&r), 0.0, 0.5, 0.0, false);
        assert_eq!(t.len(), 1);
        let tm = Measured::new(&t[0]);
        assert!((tm.length() - 60.0).abs() < 1e-2, "{}", tm.length());
        assert!((t[0].v[0] - Vec2::new(70.0, 40.0)).length() < 1e-4);
        // Offset wrapping around the start keeps one continuous piece on a closed path.
        let w = trim(&[r], 0.0, 0.25, 0.9, false);
        assert_eq!(w.len(), 1);
        assert!((Measured::new(&w[0]).length() - 30.0).abs() < 1e-2);
    }

    #[test]
    fn circle_length() {
        let e = ellipse(Vec2::ZERO, Vec2::splat(100.0), false);
        let l = Measured::new(&e).length();
        assert!((l - std::f32::consts::PI * 100.0).abs() < 0.2, "{l}");
    }

    #[test]
    fn trim_ranges() {
        assert_eq!(trim_range(0.0, 1.0, 0.3), None);
        let (a, b) = trim_range(0.8, 0.2, 0.5).unwrap();
        assert!((a - 0.7).abs() < 1e-6 && (b - 1.3).abs() < 1e-6);
        let (a, b) = trim_range(0.5, 0.5, 0.0).unwrap();
        assert_eq!(a, b);
    }
}
