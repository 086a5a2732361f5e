//! SVG frame sequences: 1–4 frames written from a grammar of the SVG that exporters produce —
//! top-level groups named by `id` or `inkscape:label` (coming and going between frames),
//! nested groups, shapes with random paths, transforms, strokes, `use` references (to
//! themselves too), gradients, clip paths, masks, patterns, blur filters, text — with hostile
//! sizes and numbers, and sometimes text damage. Loaded at ≤ 64 px and every region rendered
//! at its first and last frame: every sequence loads and renders, or is an `Err`.

use super::harness::{Files, Reader, Rng};
use fluidymation::anim::{self, LoadOptions};
use std::fmt::Write as _;
use std::path::Path;

pub const READER: Reader = Reader { name: "svg", make, check };

fn num(rng: &mut Rng, ordinary: f64) -> String {
    if rng.chance(0.99) {
        return format!("{:.1}", ordinary * rng.f64());
    }
    match rng.below(6) {
        0 => "NaN".into(),
        1 => "-1e30".into(),
        2 => "1e38".into(),
        3 => "".into(),
        4 => "abc".into(),
        _ => format!("{}", rng.hostile_f64(ordinary)),
    }
}

fn path_data(rng: &mut Rng, size: f64) -> String {
    let mut d = format!("M{} {}", num(rng, size), num(rng, size));
    for _ in 0..rng.range(1, 12) {
        let cmd = *rng.pick(&["L", "l", "H", "V", "C", "c", "Q", "S", "T", "A", "a", "Z", "z", "M", "X"]);
        let args = match cmd {
            "H" | "V" => 1,
            "C" | "c" => 6,
            "Q" | "S" => 4,
            "A" | "a" => 7,
            "Z" | "z" => 0,
            _ => 2,
        };
        d.push_str(cmd);
        for k in 0..args {
            let v = if (cmd == "A" || cmd == "a") && (k == 3 || k == 4) {
                rng.below(2).to_string()
            } else {
                num(rng, size)
            };
            let _ = write!(d, " {v}");
        }
    }
    d
}

fn transform(rng: &mut Rng, size: f64) -> String {
    match rng.below(8) {
        0 => format!(" transform=\"translate({} {})\"", num(rng, size), num(rng, size)),
        1 => format!(" transform=\"rotate({} {} {})\"", num(rng, 360.0), num(rng, size), num(rng, size)),
        2 => format!(" transform=\"scale({})\"", num(rng, 3.0)),
        3 => format!(
            " transform=\"matrix({} {} {} {} {} {})\"",
            num(rng, 2.0),
            num(rng, 2.0),
            num(rng, 2.0),
            num(rng, 2.0),
            num(rng, size),
            num(rng, size)
        ),
        4 => format!(" transform=\"skewX({})\"", num(rng, 90.0)),
        _ => String::new(),
    }
}

fn paint(rng: &mut Rng) -> String {
    let color = |rng: &mut Rng| {
        rng.pick(&["#ff0000", "#0a0", "blue", "none", "url(#g)", "url(#p)", "url(#missing)", "rgb(10,20,30)", "#zz"])
            .to_string()
    };
    let mut s = format!(" fill=\"{}\"", color(rng));
    if rng.chance(0.3) {
        let _ = write!(s, " stroke=\"{}\" stroke-width=\"{}\"", color(rng), num(rng, 8.0));
    }
    if rng.chance(0.1) {
        let _ = write!(s, " style=\"fill:{};stroke:{};opacity:{}\"", color(rng), color(rng), num(rng, 1.0));
    }
    if rng.chance(0.1) {
        let effect: &&str =
            rng.pick(&[" clip-path=\"url(#c)\"", " mask=\"url(#m)\"", " filter=\"url(#f)\"", " opacity=\"0.5\""]);
        s.push_str(effect);
    }
    s
}

fn shape(rng: &mut Rng, size: f64, depth: usize, out: &mut String) {
    let t = transform(rng, size);
    let p = paint(rng);
    match rng.below(if depth < 3 { 11 } else { 9 }) {
        0 => {
            let _ = write!(
                out,
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" rx=\"{}\"{t}{p}/>",
                num(rng, size),
                num(rng, size),
                num(rng, size),
                num(rng, size),
                num(rng, 5.0)
            );
        }
        1 => {
            let _ = write!(
                out,
                "<circle cx=\"{}\" cy=\"{}\" r=\"{}\"{t}{p}/>",
                num(rng, size),
                num(rng, size),
                num(rng, size / 2.0)
            );
        }
        2 => {
            let _ = write!(
                out,
                "<ellipse cx=\"{}\" cy=\"{}\" rx=\"{}\" ry=\"{}\"{t}{p}/>",
                num(rng, size),
                num(rng, size),
                num(rng, size),
                num(rng, size)
            );
        }
        3 | 4 => {
            let _ = write!(out, "<path d=\"{}\"{t}{p}/>", path_data(rng, size));
        }
        5 => {
            let pts: Vec<String> =
                (0..rng.range(0, 8)).map(|_| format!("{},{}", num(rng, size), num(rng, size))).collect();
            let _ = write!(out, "<polygon points=\"{}\"{t}{p}/>", pts.join(" "));
        }
        6 => {
            let _ = write!(
                out,
                "<line x1=\"0\" y1=\"0\" x2=\"{}\" y2=\"{}\" stroke=\"black\"{t}/>",
                num(rng, size),
                num(rng, size)
            );
        }
        7 => {
            let _ = write!(
                out,
                "<use href=\"#{}\" x=\"{}\"{t}/>",
                rng.pick(&["s0", "s1", "g0", "self", "nothing"]),
                num(rng, 10.0)
            );
        }
        8 => {
            let _ = write!(out, "<text x=\"5\" y=\"20\" font-size=\"{}\"{p}>paint</text>", num(rng, 30.0));
        }
        _ => {
            let _ = write!(out, "<g id=\"{}\"{t}{p}>", if rng.chance(0.2) { "self" } else { "inner" });
            for _ in 0..rng.range(0, 3) {
                shape(rng, size, depth + 1, out);
            }
            if rng.chance(0.1) {
                out.push_str("<use href=\"#self\"/>");
            }
            out.push_str("</g>");
        }
    }
}

fn defs(rng: &mut Rng, size: f64) -> String {
    let mut d = String::from("<defs>");
    if rng.chance(0.5) {
        let _ = write!(
            d,
            "<linearGradient id=\"g\" x2=\"{}\"><stop offset=\"0\" stop-color=\"red\"/><stop offset=\"{}\" stop-color=\"blue\"/></linearGradient>",
            num(rng, 1.0),
            num(rng, 1.0)
        );
    }
    if rng.chance(0.3) {
        let _ = write!(
            d,
            "<pattern id=\"p\" width=\"{}\" height=\"{}\" patternUnits=\"userSpaceOnUse\"><circle r=\"3\" cx=\"3\" cy=\"3\"/></pattern>",
            num(rng, 10.0),
            num(rng, 10.0)
        );
    }
    if rng.chance(0.3) {
        let _ = write!(
            d,
            "<clipPath id=\"c\"><circle cx=\"{}\" cy=\"{}\" r=\"{}\"/></clipPath>",
            num(rng, size),
            num(rng, size),
            num(rng, size)
        );
    }
    if rng.chance(0.3) {
        let _ = write!(
            d,
            "<mask id=\"m\"><rect width=\"{}\" height=\"{}\" fill=\"white\"/></mask>",
            num(rng, size),
            num(rng, size)
        );
    }
    if rng.chance(0.3) {
        let _ = write!(d, "<filter id=\"f\"><feGaussianBlur stdDeviation=\"{}\"/></filter>", num(rng, 20.0));
    }
    let _ = write!(d, "<path id=\"s0\" d=\"{}\"/>", path_data(rng, size));
    d.push_str("<rect id=\"s1\" width=\"10\" height=\"10\"/></defs>");
    d
}

fn frame(rng: &mut Rng, w: &str, h: &str, size: f64, names: &[&str]) -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n");
    let view =
        if rng.chance(0.3) { format!(" viewBox=\"0 0 {} {}\"", num(rng, size), num(rng, size)) } else { String::new() };
    let _ = write!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" \
         xmlns:inkscape=\"http://www.inkscape.org/namespaces/inkscape\" width=\"{w}\" height=\"{h}\"{view}>"
    );
    s.push_str(&defs(rng, size));
    for name in names {
        if rng.chance(0.2) {
            continue; // the layer is missing in this frame
        }
        if rng.chance(0.2) {
            shape(rng, size, 0, &mut s); // a loose shape: the root region
        }
        let attr = if rng.chance(0.5) {
            format!("inkscape:label=\"{name}\" id=\"l{name}\"")
        } else {
            format!("id=\"{name}\"")
        };
        let _ = write!(s, "<g {attr}{}>", transform(rng, size));
        for _ in 0..rng.range(1, 4) {
            shape(rng, size, 1, &mut s);
        }
        s.push_str("</g>");
    }
    s.push_str("</svg>\n");
    s
}

fn make(rng: &mut Rng) -> Files {
    let size = *rng.pick(&[16.0, 48.0, 64.0, 200.0]);
    let side = |rng: &mut Rng| -> String {
        if rng.chance(0.97) {
            format!("{}", size as i64)
        } else {
            rng.pick(&["0", "-5", "100%", "abc", "16385", "1e6", "20000", "1"]).to_string()
        }
    };
    let (w, h) = (side(rng), side(rng));
    let names: Vec<&str> =
        ["body", "arm", "Layer 1", "äöü", "body"].iter().copied().take(rng.range(1, 5) as usize).collect();
    let frames = rng.range(1, 4) as usize;
    let mut files = Vec::new();
    for k in 0..frames {
        let (fw, fh) = if rng.chance(0.05) { (side(rng), side(rng)) } else { (w.clone(), h.clone()) };
        let mut text = frame(rng, &fw, &fh, size, &names);
        if rng.chance(0.03) {
            let mut pos = rng.below(text.len());
            while !text.is_char_boundary(pos) {
                pos -= 1;
            }
            text = if rng.chance(0.5) {
                text[..pos].to_string()
            } else {
                format!("{}&#0;<{}", &text[..pos], &text[pos..])
            };
        }
        files.push((format!("frames/f{:02}.svg", k + 1), text.into_bytes()));
    }
    files
}

fn check(dir: &Path) {
    let frames = dir.join("frames");
    // The canvas size is known only after loading: load once at scale 1 to learn it, then
    // at the scale that makes it ≤ 64 px (what is checked is the second load).
    let Ok(a) = anim::load(&frames, &LoadOptions::default()) else { return };
    let scale = (64.0 / a.width.max(a.height) as f32).min(1.0);
    let Ok(a) = anim::load(&frames, &LoadOptions::default().scale(scale)) else { return };
    for (r, region) in a.regions.iter().enumerate().take(6) {
        for f in [region.visible.start, region.visible.end.saturating_sub(1)] {
            if let Ok(rf) = a.render(r, f) {
                assert_eq!(rf.fill.size(), (a.width as usize, a.height as usize));
            }
        }
    }
}
