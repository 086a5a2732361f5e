//! Kubelka–Munk rendering of one pigment layer over paper (Curtis et al. 1997, §5).

/// Reflectance `R` and transmittance `T` per channel of a layer with absorption `k`,
/// scattering `s` and thickness `x` (Kubelka–Munk, as in Curtis et al. 1997, eq. in §5.1).
#[inline]
pub(crate) fn layer(k: [f32; 3], s: [f32; 3], x: f32) -> ([f32; 3], [f32; 3]) {
    let mut r = [0.0; 3];
    let mut t = [1.0; 3];
    if x <= 0.0 {
        return (r, t);
    }
    for i in 0..3 {
        let s_i = s[i].max(1e-4);
        let a = 1.0 + k[i] / s_i;
        let b = (a * a - 1.0).max(0.0).sqrt();
        let bsx = (b * s_i * x).min(30.0);
        let (sh, ch) = (bsx.sinh(), bsx.cosh());
        let c = a * sh + b * ch;
        r[i] = sh / c;
        t[i] = b / c;
    }
    (r, t)
}

/// Composites a layer `(R, T)` over a background of reflectance `rp`:
/// `R + T² R_p / (1 − R R_p)`.
#[inline]
pub(crate) fn over(r: [f32; 3], t: [f32; 3], rp: [f32; 3]) -> [f32; 3] {
    let mut out = [0.0; 3];
    for i in 0..3 {
        out[i] = r[i] + t[i] * t[i] * rp[i] / (1.0 - r[i] * rp[i]).max(1e-4);
    }
    out
}

/// Linear reflectance to non-linear sRGB in `0..=1`.
#[inline]
pub(crate) fn to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thin_layer_is_transparent_thick_layer_absorbs() {
        let k = [0.22, 1.47, 0.57];
        let s = [0.05, 0.003, 0.03];
        let paper = [0.9; 3];
        let (r, t) = layer(k, s, 0.0);
        assert_eq!(over(r, t, paper), paper);
        let (r, t) = layer(k, s, 2.0);
        let c = over(r, t, paper);
        // Rose absorbs green most.
        assert!(c[1] < c[0] && c[1] < c[2] && c[1] < 0.2, "{c:?}");
    }
}
