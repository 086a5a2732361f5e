//! Serde mirror of the Lottie (Bodymovin) JSON, tolerant of the 4.x and 5.x key layouts.
//!
//! Only the structure is typed here; animatable properties keep their `k` as raw JSON because
//! its shape depends on the property kind and the exporter version (a number, an array, an
//! array of keyframes with `s`/`e` values). [`super::model`] turns this into a resolved model.

use serde::{Deserialize, Deserializer};
use serde_json::Value;

/// Accepts `true`/`false` as well as `0`/`1` (old exporters write numbers).
fn flag<'de, D: Deserializer<'de>>(d: D) -> Result<bool, D::Error> {
    let v = Value::deserialize(d)?;
    Ok(match v {
        Value::Bool(b) => b,
        Value::Number(n) => n.as_f64().is_some_and(|x| x != 0.0),
        _ => false,
    })
}

/// Accepts a number (or a numeric string, or null) as `Option<f64>`.
fn num<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let v = Value::deserialize(d)?;
    Ok(match v {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => s.trim().parse().ok(),
        Value::Bool(b) => Some(if b { 1.0 } else { 0.0 }),
        _ => None,
    })
}

/// Accepts a string or a number as an optional string (layer names, asset ids).
fn text<'de, D: Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    let v = Value::deserialize(d)?;
    Ok(match v {
        Value::String(s) => Some(s),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    })
}

/// The root object of a Lottie file.
#[derive(Deserialize, Debug, Default)]
pub struct Root {
    /// Bodymovin version that wrote the file.
    #[serde(default, deserialize_with = "text")]
    pub v: Option<String>,
    /// Frame rate.
    #[serde(default, deserialize_with = "num")]
    pub fr: Option<f64>,
    /// First frame.
    #[serde(default, deserialize_with = "num")]
    pub ip: Option<f64>,
    /// Frame after the last one.
    #[serde(default, deserialize_with = "num")]
    pub op: Option<f64>,
    /// Canvas width.
    #[serde(default, deserialize_with = "num")]
    pub w: Option<f64>,
    /// Canvas height.
    #[serde(default, deserialize_with = "num")]
    pub h: Option<f64>,
    /// 3D flag.
    #[serde(default, deserialize_with = "num")]
    pub ddd: Option<f64>,
    /// The name of the composition.
    #[serde(default, deserialize_with = "text")]
    pub nm: Option<String>,
    /// Top-level layers, top-most first.
    pub layers: Option<Vec<Layer>>,
    /// Precompositions and images.
    #[serde(default)]
    pub assets: Vec<Asset>,
    /// Fonts (text is not supported; only noticed).
    #[serde(default)]
    pub fonts: Option<Value>,
    /// Character glyphs (text is not supported; only noticed).
    #[serde(default)]
    pub chars: Option<Value>,
}

/// An entry of `assets`: a precomposition (has `layers`) or an image (has `p`).
#[derive(Deserialize, Debug, Default)]
pub struct Asset {
    /// The id layers refer to with `refId`.
    #[serde(default, deserialize_with = "text")]
    pub id: Option<String>,
    /// The layers of a precomposition.
    pub layers: Option<Vec<Layer>>,
    /// Frame rate override of a precomposition (rare).
    #[serde(default, deserialize_with = "num")]
    pub fr: Option<f64>,
    /// Image file name (images are not supported).
    #[serde(default)]
    pub p: Option<Value>,
}

/// A layer of any type; fields that do not apply to its `ty` are absent.
#[derive(Deserialize, Debug, Default)]
#[allow(non_snake_case)]
pub struct Layer {
    /// Layer type: 0 precomp, 1 solid, 2 image, 3 null, 4 shape, 5 text, …
    #[serde(default, deserialize_with = "num")]
    pub ty: Option<f64>,
    /// Name.
    #[serde(default, deserialize_with = "text")]
    pub nm: Option<String>,
    /// Index that `parent` and `tp` refer to.
    #[serde(default, deserialize_with = "num")]
    pub ind: Option<f64>,
    /// `ind` of the parent layer.
    #[serde(default, deserialize_with = "num")]
    pub parent: Option<f64>,
    /// In point (composition frames).
    #[serde(default, deserialize_with = "num")]
    pub ip: Option<f64>,
    /// Out point (composition frames).
    #[serde(default, deserialize_with = "num")]
    pub op: Option<f64>,
    /// Start time.
    #[serde(default, deserialize_with = "num")]
    pub st: Option<f64>,
    /// Time stretch.
    #[serde(default, deserialize_with = "num")]
    pub sr: Option<f64>,
    /// Hidden.
    #[serde(default, deserialize_with = "flag")]
    pub hd: bool,
    /// 3D layer flag.
    #[serde(default, deserialize_with = "num")]
    pub ddd: Option<f64>,
    /// Auto-orient along the motion path.
    #[serde(default, deserialize_with = "num")]
    pub ao: Option<f64>,
    /// Blend mode.
    #[serde(default, deserialize_with = "num")]
    pub bm: Option<f64>,
    /// Transform.
    pub ks: Option<Transform>,
    /// Masks.
    pub masksProperties: Option<Vec<Mask>>,
    /// Track matte mode of this layer (1 alpha, 2 alpha inverted, 3 luma, 4 luma inverted).
    #[serde(default, deserialize_with = "num")]
    pub tt: Option<f64>,
    /// This layer is a track matte for another.
    #[serde(default, deserialize_with = "num")]
    pub td: Option<f64>,
    /// `ind` of this layer's matte source (newer exports).
    #[serde(default, deserialize_with = "num")]
    pub tp: Option<f64>,
    /// Shape layer content.
    pub shapes: Option<Vec<Value>>,
    /// Precomp / image asset id.
    #[serde(default, deserialize_with = "text")]
    pub refId: Option<String>,
    /// Precomp width.
    #[serde(default, deserialize_with = "num")]
    pub w: Option<f64>,
    /// Precomp height.
    #[serde(default, deserialize_with = "num")]
    pub h: Option<f64>,
    /// Time remap (precomp).
    pub tm: Option<Prop>,
    /// Solid color `#rrggbb`.
    #[serde(default, deserialize_with = "text")]
    pub sc: Option<String>,
    /// Solid width.
    #[serde(default, deserialize_with = "num")]
    pub sw: Option<f64>,
    /// Solid height.
    #[serde(default, deserialize_with = "num")]
    pub sh: Option<f64>,
    /// Effects (not supported).
    pub ef: Option<Value>,
    /// Layer styles (not supported).
    pub sy: Option<Value>,
    /// Text data (not supported).
    pub t: Option<Value>,
}

/// An animatable property: `{"a": 0, "k": 5}` or `{"a": 1, "k": [keyframes]}`; a split
/// position is `{"s": true, "x": {…}, "y": {…}}`.
#[derive(Deserialize, Debug, Default, Clone)]
pub struct Prop {
    /// Animated flag (optional in old files; the shape of `k` decides).
    #[serde(default)]
    pub a: Option<Value>,
    /// The value or the keyframes.
    #[serde(default)]
    pub k: Option<Value>,
    /// Expression (a string) — or, for a split position, the X component.
    #[serde(default)]
    pub x: Option<Value>,
    /// Split position: the Y component.
    #[serde(default)]
    pub y: Option<Value>,
    /// Split position flag.
    #[serde(default)]
    pub s: Option<Value>,
}

/// A layer or group transform.
#[derive(Deserialize, Debug, Default, Clone)]
pub struct Transform {
    /// Anchor point.
    pub a: Option<Prop>,
    /// Position (maybe split).
    pub p: Option<Prop>,
    /// Scale in percent.
    pub s: Option<Prop>,
    /// Rotation in degrees (2D).
    pub r: Option<Prop>,
    /// Z rotation of a 3D layer (treated as `r`).
    pub rz: Option<Prop>,
    /// X rotation (3D, not supported).
    pub rx: Option<Prop>,
    /// Y rotation (3D, not supported).
    pub ry: Option<Prop>,
    /// Orientation (3D, not supported).
    pub or: Option<Prop>,
    /// Opacity in percent.
    pub o: Option<Prop>,
    /// Skew in degrees.
    pub sk: Option<Prop>,
    /// Skew axis in degrees.
    pub sa: Option<Prop>,
    /// Repeater: start opacity.
    pub so: Option<Prop>,
    /// Repeater: end opacity.
    pub eo: Option<Prop>,
}

/// A mask of `masksProperties`.
#[derive(Deserialize, Debug, Default, Clone)]
pub struct Mask {
    /// Name.
    #[serde(default, deserialize_with = "text")]
    pub nm: Option<String>,
    /// Mode: `a` add, `s` subtract, `i` intersect, `l` lighten, `d` darken, `f` difference, `n` none.
    #[serde(default, deserialize_with = "text")]
    pub mode: Option<String>,
    /// Inverted.
    #[serde(default, deserialize_with = "flag")]
    pub inv: bool,
    /// The mask path.
    pub pt: Option<Prop>,
    /// Opacity in percent.
    pub o: Option<Prop>,
    /// Expansion in pixels.
    pub x: Option<Prop>,
}

/// Fields shared by every shape item; the rest is read per type from the raw JSON.
#[derive(Deserialize, Debug, Default)]
pub struct ShapeHeader {
    /// Item type (`gr`, `sh`, `rc`, `el`, `sr`, `fl`, `st`, `gf`, `gs`, `tr`, `tm`, `mm`, `rp`, `rd`, …).
    #[serde(default, deserialize_with = "text")]
    pub ty: Option<String>,
    /// Name.
    #[serde(default, deserialize_with = "text")]
    pub nm: Option<String>,
    /// Hidden.
    #[serde(default, deserialize_with = "flag")]
    pub hd: bool,
}

/// A group `gr`.
#[derive(Deserialize, Debug, Default)]
pub struct Group {
    /// Items, top-most first; usually ends with a `tr`.
    #[serde(default)]
    pub it: Vec<Value>,
}

/// Geometry items `sh`, `rc`, `el`, `sr` (only the keys of the item's own type are present).
#[derive(Deserialize, Debug, Default)]
pub struct Geometry {
    /// `sh`: the path.
    pub ks: Option<Prop>,
    /// Position / center.
    pub p: Option<Prop>,
    /// Size (`rc`, `el`).
    pub s: Option<Prop>,
    /// `rc`: roundness; `sr`: rotation.
    pub r: Option<Prop>,
    /// Direction (3 = reversed).
    #[serde(default, deserialize_with = "num")]
    pub d: Option<f64>,
    /// `sr`: 1 star, 2 polygon.
    #[serde(default, deserialize_with = "num")]
    pub sy: Option<f64>,
    /// `sr`: points.
    pub pt: Option<Prop>,
    /// `sr`: inner radius.
    pub ir: Option<Prop>,
    /// `sr`: inner roundness in percent.
    pub is: Option<Prop>,
    /// `sr`: outer radius.
    pub or: Option<Prop>,
    /// `sr`: outer roundness in percent.
    pub os: Option<Prop>,
}

/// Gradient colors: `p` color stops, `k` the flat array (offset, r, g, b … then offset, alpha …).
#[derive(Deserialize, Debug, Default, Clone)]
pub struct GradientColors {
    /// Number of color stops.
    #[serde(default, deserialize_with = "num")]
    pub p: Option<f64>,
    /// The stops.
    pub k: Option<Prop>,
}

/// A dash entry of a stroke: `n` is `d` (dash), `g` (gap) or `o` (offset).
#[derive(Deserialize, Debug, Default, Clone)]
pub struct Dash {
    /// Kind.
    #[serde(default, deserialize_with = "text")]
    pub n: Option<String>,
    /// Length.
    pub v: Option<Prop>,
}

/// Styles `fl`, `st`, `gf`, `gs`.
#[derive(Deserialize, Debug, Default)]
pub struct Style {
    /// Color (`fl`, `st`).
    pub c: Option<Prop>,
    /// Opacity in percent.
    pub o: Option<Prop>,
    /// Fill rule: 1 nonzero, 2 even-odd.
    #[serde(default, deserialize_with = "num")]
    pub r: Option<f64>,
    /// Stroke width.
    pub w: Option<Prop>,
    /// Line cap: 1 butt, 2 round, 3 square.
    #[serde(default, deserialize_with = "num")]
    pub lc: Option<f64>,
    /// Line join: 1 miter, 2 round, 3 bevel.
    #[serde(default, deserialize_with = "num")]
    pub lj: Option<f64>,
    /// Miter limit.
    #[serde(default, deserialize_with = "num")]
    pub ml: Option<f64>,
    /// Dashes.
    pub d: Option<Vec<Dash>>,
    /// Gradient: start point.
    pub s: Option<Prop>,
    /// Gradient: end point.
    pub e: Option<Prop>,
    /// Gradient: 1 linear, 2 radial.
    #[serde(default, deserialize_with = "num")]
    pub t: Option<f64>,
    /// Gradient: highlight length in percent.
    pub h: Option<Prop>,
    /// Gradient: highlight angle in degrees.
    pub a: Option<Prop>,
    /// Gradient colors.
    pub g: Option<GradientColors>,
}

/// Modifiers `tm`, `rd`, `mm`, `rp`.
#[derive(Deserialize, Debug, Default)]
pub struct Modifier {
    /// Trim start in percent.
    pub s: Option<Prop>,
    /// Trim end in percent.
    pub e: Option<Prop>,
    /// Trim offset in degrees.
    pub o: Option<Prop>,
    /// Trim: 1 simultaneously, 2 individually; merge: mode 1–5.
    #[serde(default, deserialize_with = "num")]
    pub m: Option<f64>,
    /// Rounded corners radius.
    pub r: Option<Prop>,
    /// Repeater: copies.
    pub c: Option<Prop>,
    /// Repeater: transform.
    pub tr: Option<Transform>,
}
