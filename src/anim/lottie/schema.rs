//! Serde mirror of the Lottie (Bodymovin) JSON, tolerant of the 4.x and 5.x key layouts.
//!
//! Everything is typed: shape items are the [`Shape`] enum tagged by `ty` (unknown types
//! become [`Shape::Unknown`]), animatable properties are [`Prop`]s whose `k` is a
//! [`Value`]: a static value or a list of [`Keyframe`]s with `s`/`e` values and easing
//! [`Handle`]s. [`super::model`] resolves this into the model once at load time.
//!
//! Exporters disagree on the details, so the leaves are read leniently (numbers as `0`/`1`
//! booleans, numeric strings, a number wrapped in an array, colors in `0..=255`); a value
//! that cannot be read becomes [`Value::Malformed`] (the model warns and uses the default),
//! and a shape item that cannot be read is kept as its type's default with the reason in
//! [`ShapeEntry::error`]; a layer's `ty` that is not a number is kept as written, for the
//! warning that quotes it with its JSON path. Only a structure that is wrong as a whole (a
//! transform that is a number, `layers` that is not a list) fails the file.
//!
//! Keys that are only skipped (`a`, `nm`, …) are declared anyway, in their usual order: serde
//! also reads a struct from an array, by position, and a property written as an array must
//! read the same as before.

use super::geom::Bez;
use super::value::Color;
use glam::Vec2;
use serde::de::IgnoredAny;
use serde::{Deserialize, Deserializer};
use serde_json::Value as Json;

/// Largest vertex count of one path accepted from a file (safety limit).
pub const MAX_VERTICES: usize = 100_000;

// ---------------------------------------------------------------------------------------
// Lenient leaves

fn flag_of(v: &Json) -> bool {
    match v {
        Json::Bool(b) => *b,
        Json::Number(n) => n.as_f64().is_some_and(|x| x != 0.0),
        _ => false,
    }
}

/// Accepts `true`/`false` as well as `0`/`1` (old exporters write numbers).
fn flag<'de, D: Deserializer<'de>>(d: D) -> Result<bool, D::Error> {
    Ok(flag_of(&Json::deserialize(d)?))
}

fn num_of(v: &Json) -> Option<f64> {
    match v {
        Json::Number(n) => n.as_f64(),
        Json::String(s) => s.trim().parse().ok(),
        Json::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
        _ => None,
    }
}

/// Accepts a number (or a numeric string, or a boolean) as `Option<f64>`.
fn num<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    Ok(num_of(&Json::deserialize(d)?))
}

/// Like [`num`], but a present value that is not a number is kept as written (its JSON
/// text), for a message that quotes it.
fn num_or_written<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Result<f64, String>>, D::Error> {
    let v = Json::deserialize(d)?;
    Ok(Some(num_of(&v).ok_or_else(|| v.to_string())))
}

/// Like [`num`], but a present value that is not a number (nor `null`) fails the file: the
/// fields whose wrong value would silently change the animation (its size, frame rate and
/// frames, a layer's index, parent and timing). [`misshapen`] then names the field by its JSON
/// path.
fn strict_num<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let v = Json::deserialize(d)?;
    if v.is_null() {
        return Ok(None);
    }
    num_of(&v).map(Some).ok_or_else(|| serde::de::Error::custom(format!("{} is not a number", brief(&v))))
}

fn text_of(v: &Json) -> Option<String> {
    match v {
        Json::String(s) => Some(s.clone()),
        Json::Number(n) => Some(n.to_string()),
        _ => None,
    }
}

/// Accepts a string or a number as an optional string (layer names, asset ids).
fn text<'de, D: Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    Ok(text_of(&Json::deserialize(d)?))
}

/// True for a non-empty list (effects, layer styles, glyphs: only noticed).
fn non_empty<'de, D: Deserializer<'de>>(d: D) -> Result<bool, D::Error> {
    Ok(Json::deserialize(d)?.as_array().is_some_and(|a| !a.is_empty()))
}

/// A number, or the first element of an array (`[5]`).
fn number_of(v: &Json) -> Option<f32> {
    match v {
        Json::Number(n) => n.as_f64().map(|x| x as f32),
        Json::Array(a) => a.first().and_then(number_of),
        _ => None,
    }
}

/// A number or an array of numbers.
fn numbers_of(v: &Json) -> Option<Vec<f32>> {
    match v {
        Json::Number(n) => n.as_f64().map(|x| vec![x as f32]),
        Json::Array(a) => a.iter().map(|x| x.as_number().and_then(|n| n.as_f64()).map(|x| x as f32)).collect(),
        _ => None,
    }
}

fn number<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f32>, D::Error> {
    Ok(number_of(&Json::deserialize(d)?))
}

/// A spatial tangent: at least two numbers.
fn tangent<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec2>, D::Error> {
    Ok(numbers_of(&Json::deserialize(d)?).filter(|n| n.len() >= 2).map(|n| Vec2::new(n[0], n[1])))
}

/// A property value type, read leniently from the JSON of `k` or of a keyframe's `s`/`e`.
pub trait FromJson: Sized {
    /// The value, or `None` when the JSON does not have its shape.
    fn from_json(v: &Json) -> Option<Self>;
}

impl FromJson for f32 {
    fn from_json(v: &Json) -> Option<Self> {
        number_of(v)
    }
}

impl FromJson for Vec2 {
    fn from_json(v: &Json) -> Option<Self> {
        let n = numbers_of(v)?;
        match n.len() {
            0 => None,
            1 => Some(Vec2::splat(n[0])),
            _ => Some(Vec2::new(n[0], n[1])),
        }
    }
}

impl FromJson for Color {
    fn from_json(v: &Json) -> Option<Self> {
        let n = numbers_of(v)?;
        if n.len() < 3 {
            return None;
        }
        let mut c = [n[0], n[1], n[2], n.get(3).copied().unwrap_or(1.0)];
        // Some old exporters write 0..255.
        if c[..3].iter().any(|&x| x > 1.0) {
            for x in &mut c[..3] {
                *x /= 255.0;
            }
        }
        if c[3] > 1.0 {
            c[3] /= 255.0;
        }
        Some(Color(c.map(|x| if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 })))
    }
}

/// A flat list of numbers (gradient stops).
impl FromJson for Vec<f32> {
    fn from_json(v: &Json) -> Option<Self> {
        numbers_of(v)
    }
}

/// `[[x, y], …]`; `None` past [`MAX_VERTICES`] or when a point is not two numbers.
fn points(v: Option<&Json>) -> Option<Vec<Vec2>> {
    let a = v?.as_array()?;
    if a.len() > MAX_VERTICES {
        return None;
    }
    a.iter()
        .map(|p| {
            let p = p.as_array()?;
            Some(Vec2::new(p.first()?.as_f64()? as f32, p.get(1)?.as_f64()? as f32))
        })
        .collect()
}

/// A path `{"c": bool, "v": [...], "i": [...], "o": [...]}`, or a one-element array of it
/// (old exports); missing tangents are zero.
impl FromJson for Bez {
    fn from_json(v: &Json) -> Option<Self> {
        let v = match v {
            Json::Array(a) => a.first()?,
            Json::Object(_) => v,
            _ => return None,
        };
        let verts = points(v.get("v"))?;
        let n = verts.len();
        let mut inn = points(v.get("i")).unwrap_or_default();
        let mut out = points(v.get("o")).unwrap_or_default();
        inn.resize(n, Vec2::ZERO);
        out.resize(n, Vec2::ZERO);
        Some(Bez { closed: v.get("c").is_some_and(flag_of), v: verts, i: inn, o: out })
    }
}

fn leaf<'de, D: Deserializer<'de>, T: FromJson>(d: D) -> Result<Option<T>, D::Error> {
    Ok(T::from_json(&Json::deserialize(d)?))
}

/// `Some(value)` when the key is present at all (the value itself may be unreadable).
fn present<'de, D: Deserializer<'de>, T: FromJson>(d: D) -> Result<Option<Option<T>>, D::Error> {
    Ok(Some(T::from_json(&Json::deserialize(d)?)))
}

// ---------------------------------------------------------------------------------------
// Animatable properties

/// An easing handle of a keyframe: `x` and `y` per dimension (a single number applies to
/// every dimension). Empty when absent or malformed.
#[derive(Debug, Clone, Default)]
pub struct Handle {
    /// Time components.
    pub x: Vec<f32>,
    /// Value components.
    pub y: Vec<f32>,
}

fn handle<'de, D: Deserializer<'de>>(d: D) -> Result<Handle, D::Error> {
    let v = Json::deserialize(d)?;
    let part = |k: &str| v.get(k).and_then(numbers_of).unwrap_or_default();
    Ok(Handle { x: part("x"), y: part("y") })
}

/// A keyframe: `{"t": 0, "s": [..], "e": [..], "o": {..}, "i": {..}, "h": 1, "to": [..], "ti": [..]}`.
/// 5.x files give each keyframe its start value `s` (the last one has only `s`); 4.x files
/// also give the end value `e` (the last keyframe has only `t`).
#[derive(Deserialize, Debug, Clone)]
#[serde(bound(deserialize = "T: FromJson"))]
pub struct Keyframe<T> {
    /// Time (frame).
    #[serde(default, deserialize_with = "number")]
    pub t: Option<f32>,
    /// Start value.
    #[serde(default = "Option::default", deserialize_with = "leaf")]
    pub s: Option<T>,
    /// End value (4.x): `Some` when the key is present, whether or not it could be read.
    #[serde(default = "Option::default", deserialize_with = "present")]
    pub e: Option<Option<T>>,
    /// Out easing handle.
    #[serde(default, deserialize_with = "handle")]
    pub o: Handle,
    /// In easing handle.
    #[serde(default, deserialize_with = "handle")]
    pub i: Handle,
    /// Hold: the value jumps at the next keyframe.
    #[serde(default, deserialize_with = "flag")]
    pub h: bool,
    /// Spatial out tangent (positions).
    #[serde(default, deserialize_with = "tangent")]
    pub to: Option<Vec2>,
    /// Spatial in tangent (positions).
    #[serde(default, deserialize_with = "tangent")]
    pub ti: Option<Vec2>,
}

/// The `k` of an animatable property.
#[derive(Debug, Clone)]
pub enum Value<T> {
    /// One value for every frame.
    Static(T),
    /// Keyframes, in file order.
    Animated(Vec<Keyframe<T>>),
    /// Neither: the model warns and uses the property's default.
    Malformed,
}

impl<T: FromJson> Value<T> {
    fn from_json(k: &Json) -> Self {
        match k {
            Json::Array(a) if a.first().is_some_and(|f| f.is_object() && f.get("t").is_some()) => {
                if !a.iter().all(Json::is_object) {
                    return Value::Malformed;
                }
                match a.iter().map(Keyframe::deserialize).collect::<Result<Vec<_>, _>>() {
                    Ok(keys) => Value::Animated(keys),
                    Err(_) => Value::Malformed,
                }
            }
            _ => T::from_json(k).map_or(Value::Malformed, Value::Static),
        }
    }
}

impl<'de, T: FromJson> Deserialize<'de> for Value<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(Value::from_json(&Json::deserialize(d)?))
    }
}

/// `k`: absent (or null) is `None`.
fn keyed<'de, D: Deserializer<'de>, T: FromJson>(d: D) -> Result<Option<Value<T>>, D::Error> {
    Ok(Option::<Json>::deserialize(d)?.map(|k| Value::from_json(&k)))
}

/// True for an expression: a non-empty string.
fn expression<'de, D: Deserializer<'de>>(d: D) -> Result<bool, D::Error> {
    Ok(matches!(Json::deserialize(d)?, Json::String(s) if !s.is_empty()))
}

/// An animatable property: `{"a": 0, "k": 5}` or `{"a": 1, "k": [keyframes]}` (the `a` flag
/// is optional in old files; the shape of `k` decides).
#[derive(Deserialize, Debug, Clone)]
#[serde(bound(deserialize = "T: FromJson"))]
pub struct Prop<T> {
    /// Animated flag (optional in old files; the shape of `k` decides).
    #[serde(default, rename = "a")]
    _a: Option<IgnoredAny>,
    /// The value or the keyframes.
    #[serde(default = "Option::default", deserialize_with = "keyed")]
    pub k: Option<Value<T>>,
    /// Has an expression (`x`; not supported, the keyframed value is used).
    #[serde(default, deserialize_with = "expression")]
    pub x: bool,
}

/// A position: one 2D property, or split (`"s": true`) into `x` and `y` properties.
#[derive(Deserialize, Debug, Clone, Default)]
pub struct Position {
    /// Animated flag (not split).
    #[serde(default, rename = "a")]
    _a: Option<IgnoredAny>,
    /// The value or the keyframes (not split).
    #[serde(default, deserialize_with = "keyed")]
    pub k: Option<Value<Vec2>>,
    /// The expression flag (not split) or the X component (split).
    #[serde(default, deserialize_with = "split_x")]
    pub x: SplitX,
    /// The Y component (split).
    #[serde(default, deserialize_with = "component")]
    pub y: Option<Prop<f32>>,
    /// Split into `x` and `y`.
    #[serde(default, deserialize_with = "split")]
    pub s: bool,
}

/// The `x` of a [`Position`]: an expression when not split, a component when split.
#[derive(Debug, Clone, Default)]
pub struct SplitX {
    /// `x` is an expression.
    pub expression: bool,
    /// `x` is a property.
    pub component: Option<Prop<f32>>,
}

fn split<'de, D: Deserializer<'de>>(d: D) -> Result<bool, D::Error> {
    let v = Json::deserialize(d)?;
    Ok(v.as_bool() == Some(true) || v.as_f64() == Some(1.0))
}

fn component<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Prop<f32>>, D::Error> {
    Ok(Prop::deserialize(&Json::deserialize(d)?).ok())
}

fn split_x<'de, D: Deserializer<'de>>(d: D) -> Result<SplitX, D::Error> {
    let v = Json::deserialize(d)?;
    Ok(SplitX { expression: matches!(&v, Json::String(s) if !s.is_empty()), component: Prop::deserialize(&v).ok() })
}

// ---------------------------------------------------------------------------------------
// Composition and layers

/// The root object of a Lottie file.
#[derive(Deserialize, Debug, Default)]
pub struct Root {
    /// Bodymovin version that wrote the file.
    #[serde(default, rename = "v")]
    _v: Option<IgnoredAny>,
    /// Frame rate.
    #[serde(default, deserialize_with = "strict_num")]
    pub fr: Option<f64>,
    /// First frame.
    #[serde(default, deserialize_with = "strict_num")]
    pub ip: Option<f64>,
    /// Frame after the last one.
    #[serde(default, deserialize_with = "strict_num")]
    pub op: Option<f64>,
    /// Canvas width.
    #[serde(default, deserialize_with = "strict_num")]
    pub w: Option<f64>,
    /// Canvas height.
    #[serde(default, deserialize_with = "strict_num")]
    pub h: Option<f64>,
    /// 3D flag.
    #[serde(default, deserialize_with = "num")]
    pub ddd: Option<f64>,
    /// The name of the composition.
    #[serde(default, rename = "nm")]
    _nm: Option<IgnoredAny>,
    /// Top-level layers, top-most first.
    pub layers: Option<Vec<Layer>>,
    /// Precompositions and images.
    #[serde(default)]
    pub assets: Vec<Asset>,
    /// Fonts for text (not supported).
    #[serde(default, rename = "fonts")]
    _fonts: Option<IgnoredAny>,
    /// Character glyphs for text (not supported; only noticed).
    #[serde(default, deserialize_with = "non_empty")]
    pub chars: bool,
}

/// An entry of `assets`: a precomposition (has `layers`) or an image.
#[derive(Deserialize, Debug, Default)]
pub struct Asset {
    /// The id layers refer to with `refId`.
    #[serde(default, deserialize_with = "text")]
    pub id: Option<String>,
    /// The layers of a precomposition.
    pub layers: Option<Vec<Layer>>,
}

/// A layer of any type; fields that do not apply to its `ty` are absent.
#[derive(Deserialize, Debug, Default)]
#[allow(non_snake_case)]
pub struct Layer {
    /// Layer type: 0 precomp, 1 solid, 2 image, 3 null, 4 shape, 5 text, …; `Err` holds the
    /// JSON as written when it is not a number (`"abc"`, `null`).
    #[serde(default, deserialize_with = "num_or_written")]
    pub ty: Option<Result<f64, String>>,
    /// Name.
    #[serde(default, deserialize_with = "text")]
    pub nm: Option<String>,
    /// Index that `parent` and `tp` refer to.
    #[serde(default, deserialize_with = "strict_num")]
    pub ind: Option<f64>,
    /// `ind` of the parent layer.
    #[serde(default, deserialize_with = "strict_num")]
    pub parent: Option<f64>,
    /// In point (composition frames).
    #[serde(default, deserialize_with = "strict_num")]
    pub ip: Option<f64>,
    /// Out point (composition frames).
    #[serde(default, deserialize_with = "strict_num")]
    pub op: Option<f64>,
    /// Start time.
    #[serde(default, deserialize_with = "strict_num")]
    pub st: Option<f64>,
    /// Time stretch.
    #[serde(default, deserialize_with = "strict_num")]
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
    #[serde(default, deserialize_with = "strict_num")]
    pub tp: Option<f64>,
    /// Shape layer content.
    pub shapes: Option<Vec<ShapeEntry>>,
    /// Precomp / image asset id.
    #[serde(default, deserialize_with = "text")]
    pub refId: Option<String>,
    /// Precomp width.
    #[serde(default, deserialize_with = "num")]
    pub w: Option<f64>,
    /// Precomp height.
    #[serde(default, deserialize_with = "num")]
    pub h: Option<f64>,
    /// Time remap (precomp), in seconds.
    pub tm: Option<Prop<f32>>,
    /// Solid color `#rrggbb`.
    #[serde(default, deserialize_with = "text")]
    pub sc: Option<String>,
    /// Solid width.
    #[serde(default, deserialize_with = "num")]
    pub sw: Option<f64>,
    /// Solid height.
    #[serde(default, deserialize_with = "num")]
    pub sh: Option<f64>,
    /// Effects present (not supported).
    #[serde(default, deserialize_with = "non_empty")]
    pub ef: bool,
    /// Layer styles present (not supported).
    #[serde(default, deserialize_with = "non_empty")]
    pub sy: bool,
}

/// A short description of a JSON value for a message: `"abc"`, `5`, `null`, `an object`, `a
/// list` (long strings are cut).
pub fn brief(v: &Json) -> String {
    match v {
        Json::Object(_) => "an object".into(),
        Json::Array(_) => "a list".into(),
        Json::String(s) if s.chars().count() > 40 => format!("\"{}…\"", s.chars().take(40).collect::<String>()),
        _ => v.to_string(),
    }
}

/// Why the JSON `root`, which the typed reading of this module refused, is not a Lottie file,
/// by the JSON path of the first field of the wrong type (`layers[1].ks is 5, expected an
/// object (the layer's transform)`); `None` when it finds nothing (the reader's own message is
/// then the best there is).
pub fn misshapen(root: &Json) -> Option<String> {
    let Json::Object(root) = root else { return Some("the top level is not a JSON object".into()) };
    let numbers = [
        ("fr", "the frame rate"),
        ("ip", "the first frame"),
        ("op", "the end frame"),
        ("w", "the canvas width"),
        ("h", "the canvas height"),
    ];
    if let Some(why) = wrong_number(root, &numbers, "") {
        return Some(why);
    }
    if let Some(why) = root.get("layers").and_then(|l| misshapen_layers(l, "layers")) {
        return Some(why);
    }
    match root.get("assets") {
        None => None,
        Some(Json::Array(assets)) => assets.iter().enumerate().find_map(|(i, a)| match a {
            Json::Object(a) => a.get("layers").and_then(|l| misshapen_layers(l, &format!("assets[{i}].layers"))),
            other => {
                Some(format!("assets[{i}] is {}, expected an object (a precomposition or an image)", brief(other)))
            }
        }),
        Some(other) => Some(format!("assets is {}, expected a list (of precompositions and images)", brief(other))),
    }
}

/// The first of the fields `keys` (with what each is, for the message) of `object` that is
/// present but neither a number nor `null`, named with the JSON path prefix `at`:
/// `layers[0].ind is "q", expected a number (…)`.
fn wrong_number(object: &serde_json::Map<String, Json>, keys: &[(&str, &str)], at: &str) -> Option<String> {
    keys.iter().find_map(|&(key, what)| {
        let v = object.get(key).filter(|v| !v.is_null() && num_of(v).is_none())?;
        Some(format!("{at}{key} is {}, expected a number ({what})", brief(v)))
    })
}

/// [`misshapen`] for a list of layers at JSON path `at`.
fn misshapen_layers(layers: &Json, at: &str) -> Option<String> {
    let layers = match layers {
        Json::Null => return None,
        Json::Array(l) => l,
        other => return Some(format!("{at} is {}, expected a list of layers", brief(other))),
    };
    let numbers = [
        ("ind", "the layer's index, which 'parent' and 'tp' refer to"),
        ("parent", "the 'ind' of the parent layer"),
        ("tp", "the 'ind' of the track matte layer"),
        ("ip", "the layer's in point"),
        ("op", "the layer's out point"),
        ("st", "the layer's start time"),
        ("sr", "the layer's time stretch"),
    ];
    let parts = [
        ("ks", "an object (the layer's transform)", Json::is_object as fn(&Json) -> bool),
        ("shapes", "a list of shape items", Json::is_array),
        ("masksProperties", "a list of masks", Json::is_array),
    ];
    layers.iter().enumerate().find_map(|(i, layer)| {
        let at = format!("{at}[{i}]");
        let Json::Object(layer) = layer else {
            return Some(format!("{at} is {}, expected an object (a layer)", brief(layer)));
        };
        if let Some(why) = wrong_number(layer, &numbers, &format!("{at}.")) {
            return Some(why);
        }
        for (key, what, is) in parts {
            if let Some(v) = layer.get(key).filter(|v| !v.is_null() && !is(v)) {
                return Some(format!("{at}.{key} is {}, expected {what}", brief(v)));
            }
        }
        None
    })
}

/// A layer or group transform (a repeater's also has `so`/`eo`).
#[derive(Deserialize, Debug, Default, Clone)]
pub struct Transform {
    /// Anchor point.
    pub a: Option<Prop<Vec2>>,
    /// Position (maybe split).
    pub p: Option<Position>,
    /// Scale in percent.
    pub s: Option<Prop<Vec2>>,
    /// Rotation in degrees (2D).
    pub r: Option<Prop<f32>>,
    /// Z rotation of a 3D layer (treated as `r`).
    pub rz: Option<Prop<f32>>,
    /// X rotation (3D, not supported; only noticed).
    pub rx: Option<IgnoredAny>,
    /// Y rotation (3D, not supported; only noticed).
    pub ry: Option<IgnoredAny>,
    /// Orientation (3D, not supported; only noticed).
    pub or: Option<IgnoredAny>,
    /// Opacity in percent.
    pub o: Option<Prop<f32>>,
    /// Skew in degrees.
    pub sk: Option<Prop<f32>>,
    /// Skew axis in degrees.
    pub sa: Option<Prop<f32>>,
    /// Repeater: start opacity.
    pub so: Option<Prop<f32>>,
    /// Repeater: end opacity.
    pub eo: Option<Prop<f32>>,
}

/// A mask of `masksProperties`.
#[derive(Deserialize, Debug, Clone)]
pub struct Mask {
    /// Name.
    #[serde(default, rename = "nm")]
    _nm: Option<IgnoredAny>,
    /// Mode: `a` add, `s` subtract, `i` intersect, `l` lighten, `d` darken, `f` difference, `n` none.
    #[serde(default, deserialize_with = "text")]
    pub mode: Option<String>,
    /// Inverted.
    #[serde(default, deserialize_with = "flag")]
    pub inv: bool,
    /// The mask path.
    pub pt: Option<Prop<Bez>>,
    /// Opacity in percent.
    pub o: Option<Prop<f32>>,
    /// Expansion in pixels.
    pub x: Option<Prop<f32>>,
}

// ---------------------------------------------------------------------------------------
// Shapes

/// An item of a shape list with what every item has. Never fails: an item that is not an
/// object, or has an unknown `ty`, is [`Shape::Unknown`]; one that cannot be read is its
/// type's default with the reason in `error`.
#[derive(Debug)]
pub struct ShapeEntry {
    /// The `ty` as written (`""` when missing).
    pub ty: String,
    /// Hidden (`hd`): skipped.
    pub hidden: bool,
    /// The item.
    pub shape: Shape,
    /// Why the item could not be read (then `shape` is the default of its type).
    pub error: Option<String>,
}

impl<'de> Deserialize<'de> for ShapeEntry {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Json::deserialize(d)?;
        let Header { ty, hd: hidden, .. } = Header::deserialize(&v).unwrap_or_default();
        let ty = ty.unwrap_or_default();
        let (shape, error) = match Shape::deserialize(&v) {
            Ok(shape) => (shape, None),
            Err(e) => match Shape::default_of(&ty) {
                Some(shape) => (shape, Some(e.to_string())),
                None => (Shape::Unknown, None),
            },
        };
        Ok(ShapeEntry { ty, hidden, shape, error })
    }
}

/// The keys every shape item has, read on their own (a malformed item keeps them).
#[derive(Deserialize, Default)]
struct Header {
    #[serde(default, deserialize_with = "text")]
    ty: Option<String>,
    #[serde(default, rename = "nm")]
    _nm: Option<IgnoredAny>,
    #[serde(default, deserialize_with = "flag")]
    hd: bool,
}

/// A shape item, by its `ty`.
#[derive(Deserialize, Debug)]
#[serde(tag = "ty")]
pub enum Shape {
    /// `gr`: a group.
    #[serde(rename = "gr")]
    Group(Group),
    /// `sh`: a free path.
    #[serde(rename = "sh")]
    Path(Path),
    /// `rc`: a rectangle.
    #[serde(rename = "rc")]
    Rect(Rect),
    /// `el`: an ellipse.
    #[serde(rename = "el")]
    Ellipse(Ellipse),
    /// `sr`: a star or polygon.
    #[serde(rename = "sr")]
    Star(Star),
    /// `fl`: a solid fill.
    #[serde(rename = "fl")]
    Fill(Fill),
    /// `st`: a solid stroke.
    #[serde(rename = "st")]
    Stroke(Stroke),
    /// `gf`: a gradient fill.
    #[serde(rename = "gf")]
    GradientFill(GradientFill),
    /// `gs`: a gradient stroke.
    #[serde(rename = "gs")]
    GradientStroke(GradientStroke),
    /// `tr`: the transform of the enclosing group.
    #[serde(rename = "tr")]
    Transform(Transform),
    /// `tm`: trim paths.
    #[serde(rename = "tm")]
    Trim(Trim),
    /// `rd`: rounded corners.
    #[serde(rename = "rd")]
    RoundCorners(RoundCorners),
    /// `mm`: merge paths.
    #[serde(rename = "mm")]
    Merge(Merge),
    /// `rp`: a repeater.
    #[serde(rename = "rp")]
    Repeater(Repeater),
    /// `pb`: pucker/bloat (not supported).
    #[serde(rename = "pb")]
    PuckerBloat,
    /// `tw`: twist (not supported).
    #[serde(rename = "tw")]
    Twist,
    /// `op`: offset path (not supported).
    #[serde(rename = "op")]
    OffsetPath,
    /// `zz`: zig-zag (not supported).
    #[serde(rename = "zz")]
    ZigZag,
    /// Any other `ty` (text shapes, newer modifiers, typos).
    #[serde(other)]
    Unknown,
}

impl Shape {
    /// The item of type `ty` with every field absent; `None` for an unknown type.
    fn default_of(ty: &str) -> Option<Shape> {
        Some(match ty {
            "gr" => Shape::Group(Group::default()),
            "sh" => Shape::Path(Path::default()),
            "rc" => Shape::Rect(Rect::default()),
            "el" => Shape::Ellipse(Ellipse::default()),
            "sr" => Shape::Star(Star::default()),
            "fl" => Shape::Fill(Fill::default()),
            "st" => Shape::Stroke(Stroke::default()),
            "gf" => Shape::GradientFill(GradientFill::default()),
            "gs" => Shape::GradientStroke(GradientStroke::default()),
            "tr" => Shape::Transform(Transform::default()),
            "tm" => Shape::Trim(Trim::default()),
            "rd" => Shape::RoundCorners(RoundCorners::default()),
            "mm" => Shape::Merge(Merge::default()),
            "rp" => Shape::Repeater(Repeater::default()),
            "pb" => Shape::PuckerBloat,
            "tw" => Shape::Twist,
            "op" => Shape::OffsetPath,
            "zz" => Shape::ZigZag,
            _ => return None,
        })
    }
}

/// A group `gr`.
#[derive(Deserialize, Debug, Default)]
pub struct Group {
    /// Items, top-most first; usually ends with a `tr`.
    #[serde(default)]
    pub it: Vec<ShapeEntry>,
}

/// A path `sh`.
#[derive(Deserialize, Debug, Default)]
pub struct Path {
    /// The path.
    pub ks: Option<Prop<Bez>>,
}

/// A rectangle `rc`.
#[derive(Deserialize, Debug, Default)]
pub struct Rect {
    /// Center.
    pub p: Option<Prop<Vec2>>,
    /// Size.
    pub s: Option<Prop<Vec2>>,
    /// Corner radius.
    pub r: Option<Prop<f32>>,
    /// Direction (3 = reversed).
    #[serde(default, deserialize_with = "num")]
    pub d: Option<f64>,
}

/// An ellipse `el`.
#[derive(Deserialize, Debug, Default)]
pub struct Ellipse {
    /// Center.
    pub p: Option<Prop<Vec2>>,
    /// Size.
    pub s: Option<Prop<Vec2>>,
    /// Direction (3 = reversed).
    #[serde(default, deserialize_with = "num")]
    pub d: Option<f64>,
}

/// A polystar `sr`.
#[derive(Deserialize, Debug, Default)]
pub struct Star {
    /// 1 star, 2 polygon.
    #[serde(default, deserialize_with = "num")]
    pub sy: Option<f64>,
    /// Center.
    pub p: Option<Prop<Vec2>>,
    /// Points.
    pub pt: Option<Prop<f32>>,
    /// Rotation in degrees.
    pub r: Option<Prop<f32>>,
    /// Inner radius.
    pub ir: Option<Prop<f32>>,
    /// Inner roundness in percent.
    pub is: Option<Prop<f32>>,
    /// Outer radius.
    pub or: Option<Prop<f32>>,
    /// Outer roundness in percent.
    pub os: Option<Prop<f32>>,
    /// Direction (3 = reversed).
    #[serde(default, deserialize_with = "num")]
    pub d: Option<f64>,
}

/// A solid fill `fl`.
#[derive(Deserialize, Debug, Default)]
pub struct Fill {
    /// Color.
    pub c: Option<Prop<Color>>,
    /// Opacity in percent.
    pub o: Option<Prop<f32>>,
    /// Fill rule: 1 nonzero, 2 even-odd.
    #[serde(default, deserialize_with = "num")]
    pub r: Option<f64>,
}

/// A solid stroke `st`.
#[derive(Deserialize, Debug, Default)]
pub struct Stroke {
    /// Color.
    pub c: Option<Prop<Color>>,
    /// Opacity in percent.
    pub o: Option<Prop<f32>>,
    /// Width, caps, joins, dashes.
    #[serde(flatten)]
    pub line: Line,
}

/// A gradient fill `gf`.
#[derive(Deserialize, Debug, Default)]
pub struct GradientFill {
    /// Opacity in percent.
    pub o: Option<Prop<f32>>,
    /// Fill rule: 1 nonzero, 2 even-odd.
    #[serde(default, deserialize_with = "num")]
    pub r: Option<f64>,
    /// The gradient.
    #[serde(flatten)]
    pub gradient: Gradient,
}

/// A gradient stroke `gs`.
#[derive(Deserialize, Debug, Default)]
pub struct GradientStroke {
    /// Opacity in percent.
    pub o: Option<Prop<f32>>,
    /// The gradient.
    #[serde(flatten)]
    pub gradient: Gradient,
    /// Width, caps, joins, dashes.
    #[serde(flatten)]
    pub line: Line,
}

/// The stroke settings of `st` and `gs`.
#[derive(Deserialize, Debug, Default)]
pub struct Line {
    /// Width.
    pub w: Option<Prop<f32>>,
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
}

/// A dash entry of a stroke: `n` is `d` (dash), `g` (gap) or `o` (offset).
#[derive(Deserialize, Debug, Clone)]
pub struct Dash {
    /// Kind.
    #[serde(default, deserialize_with = "text")]
    pub n: Option<String>,
    /// Length.
    pub v: Option<Prop<f32>>,
}

/// The gradient of `gf` and `gs`.
#[derive(Deserialize, Debug, Default)]
pub struct Gradient {
    /// Start point.
    pub s: Option<Prop<Vec2>>,
    /// End point.
    pub e: Option<Prop<Vec2>>,
    /// 1 linear, 2 radial.
    #[serde(default, deserialize_with = "num")]
    pub t: Option<f64>,
    /// Highlight length in percent.
    pub h: Option<Prop<f32>>,
    /// Highlight angle in degrees.
    pub a: Option<Prop<f32>>,
    /// Colors.
    pub g: Option<GradientColors>,
}

/// Gradient colors: `p` color stops, `k` the flat array (offset, r, g, b … then offset, alpha …).
#[derive(Deserialize, Debug, Default, Clone)]
pub struct GradientColors {
    /// Number of color stops.
    #[serde(default, deserialize_with = "num")]
    pub p: Option<f64>,
    /// The stops.
    pub k: Option<Prop<Vec<f32>>>,
}

/// Trim paths `tm`.
#[derive(Deserialize, Debug, Default)]
pub struct Trim {
    /// Start in percent.
    pub s: Option<Prop<f32>>,
    /// End in percent.
    pub e: Option<Prop<f32>>,
    /// Offset in degrees.
    pub o: Option<Prop<f32>>,
    /// 1 simultaneously, 2 individually.
    #[serde(default, deserialize_with = "num")]
    pub m: Option<f64>,
}

/// Rounded corners `rd`.
#[derive(Deserialize, Debug, Default)]
pub struct RoundCorners {
    /// Radius.
    pub r: Option<Prop<f32>>,
}

/// Merge paths `mm`.
#[derive(Deserialize, Debug, Default)]
pub struct Merge {
    /// Mode: 1 merge, 2 add, 3 subtract, 4 intersect, 5 exclude.
    #[serde(default, deserialize_with = "num")]
    pub m: Option<f64>,
}

/// A repeater `rp`.
#[derive(Deserialize, Debug, Default)]
pub struct Repeater {
    /// Copies.
    pub c: Option<Prop<f32>>,
    /// Offset (in copies).
    pub o: Option<Prop<f32>>,
    /// Composite: 1 above, 2 below.
    #[serde(default, deserialize_with = "num")]
    pub m: Option<f64>,
    /// Per-copy transform, with start and end opacity.
    pub tr: Option<Transform>,
}
