//! sRGB transfer functions (exact and table-driven) and small color helpers.
//!
//! Images hold non-linear sRGB; every physical computation of this module (optical density,
//! glazing, alpha blending) happens in linear light.

use crate::img::Rgb;
use std::sync::LazyLock;

/// Table resolution of the fast transfer functions (entries − 1).
const LUT_STEPS: usize = 4096;

/// sRGB component (`0..=1`) to linear light (`0..=1`), exact formula (IEC 61966-2-1).
/// Values outside `0..=1` are clamped; NaN becomes 0.
pub fn srgb_to_linear(v: f32) -> f32 {
    let v = sanitize(v);
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4).min(1.0) }
}

/// Linear light (`0..=1`) to an sRGB component (`0..=1`), exact formula.
/// Values outside `0..=1` are clamped; NaN becomes 0.
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = sanitize(v);
    if v <= 0.003_130_8 {
        v * 12.92
    } else if v >= 1.0 {
        1.0 // exact, where the formula rounds to 0.99999994
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Clamps into `0..=1`, mapping NaN to 0.
#[inline]
#[allow(clippy::manual_clamp)] // `clamp` would keep NaN
pub(crate) fn sanitize(v: f32) -> f32 {
    // `max` returns the other operand when one is NaN.
    v.max(0.0).min(1.0)
}

static TO_LINEAR: LazyLock<Vec<f32>> =
    LazyLock::new(|| (0..=LUT_STEPS).map(|i| srgb_to_linear(i as f32 / LUT_STEPS as f32)).collect());
static TO_SRGB: LazyLock<Vec<f32>> =
    LazyLock::new(|| (0..=LUT_STEPS).map(|i| linear_to_srgb(i as f32 / LUT_STEPS as f32)).collect());

#[inline(always)]
fn lookup(table: &[f32], v: f32) -> f32 {
    let x = sanitize(v) * LUT_STEPS as f32;
    let i = (x as usize).min(LUT_STEPS - 1);
    let f = x - i as f32;
    table[i] * (1.0 - f) + table[i + 1] * f
}

static LN_LINEAR: LazyLock<Vec<f32>> = LazyLock::new(|| {
    (0..=LUT_STEPS).map(|i| srgb_to_linear(i as f32 / LUT_STEPS as f32).max(super::INTENSITY_FLOOR).ln()).collect()
});

/// `ln max(srgb_to_linear(v), 10⁻⁴)` from one table (absolute error < 10⁻⁴ for `v > 0.01`;
/// up to 0.2 around the floor's kink at `v ≈ 0.0013`, i.e. for black pixels of density ≈ 9):
/// the optical density of an sRGB component up to a constant.
#[inline]
pub(crate) fn ln_linear(c: Rgb) -> Rgb {
    let table: &[f32] = &LN_LINEAR;
    [lookup(table, c[0]), lookup(table, c[1]), lookup(table, c[2])]
}

/// Fast [`srgb_to_linear`] (table + linear interpolation, error < 1e-5).
#[cfg(test)]
pub(crate) fn to_linear(v: f32) -> f32 {
    lookup(&TO_LINEAR, v)
}

/// Fast [`linear_to_srgb`] (table + linear interpolation, error < 1e-4, far below 1/255).
#[cfg(test)]
pub(crate) fn to_srgb(v: f32) -> f32 {
    lookup(&TO_SRGB, v)
}

/// Fast sRGB → linear of a color (table + linear interpolation, error < 1e-5).
#[inline]
pub(crate) fn rgb_to_linear(c: Rgb) -> Rgb {
    let table: &[f32] = &TO_LINEAR;
    [lookup(table, c[0]), lookup(table, c[1]), lookup(table, c[2])]
}

/// Fast linear → sRGB of a color (table + linear interpolation, error < 1e-4, far below 1/255).
#[inline]
pub(crate) fn rgb_to_srgb(c: Rgb) -> Rgb {
    let table: &[f32] = &TO_SRGB;
    [lookup(table, c[0]), lookup(table, c[1]), lookup(table, c[2])]
}

/// `e^x` for `x ≤ 0` (larger `x` is treated as 0), relative error < 5·10⁻⁶: `2^i · 2^f` with
/// `i` the integer nearest to `x·log₂e`, the exponent set through the float's bits, and a
/// degree-5 Taylor polynomial for `2^f`, `f ∈ [−½, ½]`. Deterministic on every platform.
#[inline(always)]
pub(crate) fn fast_exp(x: f32) -> f32 {
    let t = x.clamp(-125.0 * std::f32::consts::LN_2, 0.0) * std::f32::consts::LOG2_E;
    // Round to the nearest integer with the 1.5·2²³ trick (no float → int conversion): the
    // integer ends up in the low mantissa bits.
    const MAGIC: f32 = 12_582_912.0;
    let shifted = t + MAGIC;
    let i = shifted.to_bits() as i32 - MAGIC.to_bits() as i32;
    let f = (t - (shifted - MAGIC)) * std::f32::consts::LN_2; // in [−ln2/2, ln2/2]
    let p = 1.0 + f * (1.0 + f * (0.5 + f * (1.0 / 6.0 + f * (1.0 / 24.0 + f * (1.0 / 120.0)))));
    f32::from_bits(((i + 127) as u32) << 23) * p
}

/// `ln x` for positive finite `x` (absolute error < 10⁻⁶); `x ≤ 0` or NaN gives `ln 10⁻³⁰`.
/// Exponent bits plus the `atanh` series of the mantissa scaled into `[√½, √2)`.
#[inline(always)]
pub(crate) fn fast_ln(x: f32) -> f32 {
    let x = if x > 1e-30 { x } else { 1e-30 };
    let bits = x.to_bits();
    let mut e = ((bits >> 23) & 0xff) as i32 - 127;
    let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000); // [1, 2)
    if m > std::f32::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let ln_m = 2.0 * s * (1.0 + s2 * (1.0 / 3.0 + s2 * (0.2 + s2 * (1.0 / 7.0 + s2 * (1.0 / 9.0)))));
    e as f32 * std::f32::consts::LN_2 + ln_m
}

/// Parses a color: `#rgb`, `#rgba`, `#rrggbb`, `#rrggbbaa` (the `#` is optional) or one of the
/// names `white`, `black`, `gray`/`grey`, `red`, `green`, `blue`, `yellow`. Returns straight
/// sRGB RGBA in `0..=1`.
pub fn parse_color(s: &str) -> Option<[f32; 4]> {
    let s = s.trim();
    let named = match s.to_ascii_lowercase().as_str() {
        "white" => Some([1.0, 1.0, 1.0, 1.0]),
        "black" => Some([0.0, 0.0, 0.0, 1.0]),
        "gray" | "grey" => Some([0.5, 0.5, 0.5, 1.0]),
        "red" => Some([1.0, 0.0, 0.0, 1.0]),
        "green" => Some([0.0, 128.0 / 255.0, 0.0, 1.0]),
        "blue" => Some([0.0, 0.0, 1.0, 1.0]),
        "yellow" => Some([1.0, 1.0, 0.0, 1.0]),
        _ => None,
    };
    if named.is_some() {
        return named;
    }
    let h = s.strip_prefix('#').unwrap_or(s);
    if !h.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let digit = |i: usize| u8::from_str_radix(&h[i..i + 1], 16).ok().map(|v| (v * 17) as f32 / 255.0);
    let byte = |i: usize| u8::from_str_radix(&h[i..i + 2], 16).ok().map(|v| v as f32 / 255.0);
    match h.len() {
        3 => Some([digit(0)?, digit(1)?, digit(2)?, 1.0]),
        4 => Some([digit(0)?, digit(1)?, digit(2)?, digit(3)?]),
        6 => Some([byte(0)?, byte(2)?, byte(4)?, 1.0]),
        8 => Some([byte(0)?, byte(2)?, byte(4)?, byte(6)?]),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transfer_functions_round_trip_and_tables_are_accurate() {
        for i in 0..=1000 {
            let v = i as f32 / 1000.0;
            assert!((linear_to_srgb(srgb_to_linear(v)) - v).abs() < 1e-5);
            assert!((to_linear(v) - srgb_to_linear(v)).abs() < 1e-5, "{v}");
            assert!((to_srgb(v) - linear_to_srgb(v)).abs() < 1e-4, "{v}");
        }
        assert_eq!(to_linear(f32::NAN), 0.0);
        assert_eq!(to_srgb(2.0), 1.0);
        assert_eq!((to_srgb(1.0), to_linear(1.0), to_srgb(0.0), to_linear(0.0)), (1.0, 1.0, 0.0, 0.0));
    }

    #[test]
    fn fast_exp_and_ln_are_accurate() {
        for i in 0..=20_000 {
            let x = -(i as f32) * 0.001; // 0 .. -20
            let (fast, exact) = (fast_exp(x), x.exp());
            assert!((fast - exact).abs() <= 5e-6 * exact, "exp({x}): {fast} vs {exact}");
        }
        assert_eq!(fast_exp(0.0), 1.0);
        assert!(fast_exp(-200.0) >= 0.0 && fast_exp(-200.0) < 1e-30);
        for i in 1..=20_000 {
            let x = i as f32 / 10_000.0; // 0.0001 .. 2
            let (fast, exact) = (fast_ln(x), x.ln());
            assert!((fast - exact).abs() < 1e-6, "ln({x}): {fast} vs {exact}");
        }
        assert_eq!(fast_ln(1.0), 0.0);
        assert!(fast_ln(0.0) < -60.0 && fast_ln(f32::NAN) < -60.0);
    }

    #[test]
    fn ln_linear_table_is_accurate() {
        for i in 0..=10_000 {
            let v = i as f32 / 10_000.0;
            let exact = srgb_to_linear(v).max(1e-4).ln();
            let tol = if v > 0.01 { 1e-4 } else { 0.2 };
            assert!((ln_linear([v; 3])[0] - exact).abs() < tol, "{v}");
        }
    }

    #[test]
    fn colors_parse() {
        assert_eq!(parse_color("#fff"), Some([1.0; 4]));
        assert_eq!(parse_color("ff000080").map(|c| c[3]), Some(128.0 / 255.0));
        assert_eq!(parse_color("#336699"), Some([0.2, 0.4, 0.6, 1.0]));
        assert_eq!(parse_color("White"), Some([1.0; 4]));
        assert_eq!(parse_color("#12345"), None);
        assert_eq!(parse_color("paper.png"), None);
        assert_eq!(parse_color("#ééé"), None);
    }
}
