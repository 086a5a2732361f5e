//! The options structs as a library user sees them: `#[non_exhaustive]`, built with setters, and
//! stored in the same formats as before (`exemplar.toml`'s `[generator]` table, the eval JSON).

use fluidymation::eval::{EvalOptions, RimParams};
use fluidymation::exemplar::generate::{GeneratorParams, Pigment};
use fluidymation::guide::GuideParams;
use fluidymation::quality::{SuiteOptions, TargetKind};
use std::path::{Path, PathBuf};

/// Every bundled generated exemplar's `[generator]` table reads back into [`GeneratorParams`] and
/// is written again key for key, value for value.
#[test]
fn bundled_generator_tables_round_trip() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("exemplars");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path().join("exemplar.toml");
        let Ok(text) = std::fs::read_to_string(&path) else { continue };
        let meta: toml::Table = text.parse().unwrap();
        let Some(table) = meta.get("generator").and_then(|g| g.as_table()) else { continue };
        let params: GeneratorParams = table.clone().try_into().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(&params.to_table(), table, "{}", path.display());
        seen += 1;
    }
    assert!(seen >= 5, "bundled exemplars with a [generator] table: {seen}");
}

/// The `[generator]` table's keys are the field names, as before the struct was non-exhaustive.
#[test]
fn generator_table_keys() {
    let p = GeneratorParams::default().size(96, 80).pigment(Pigment::Ink).flow([0.1, -0.05]).drops(3);
    let t = p.to_table();
    let keys: Vec<&str> = t.keys().map(String::as_str).collect();
    assert_eq!(
        keys,
        [
            "bloom",
            "drop_radius",
            "drops",
            "drying",
            "flow",
            "fps",
            "frames",
            "grain",
            "granulation",
            "height",
            "load",
            "pigment",
            "rim",
            "seed",
            "steps_per_frame",
            "width"
        ]
    );
    assert_eq!(t["pigment"].as_str(), Some("ink"));
    assert_eq!((t["width"].as_integer(), t["height"].as_integer()), (Some(96), Some(80)));
    // Missing keys take the defaults; unknown keys are refused.
    let q: GeneratorParams = toml::from_str("drops = 3\n").unwrap();
    assert_eq!(q, GeneratorParams::default().drops(3));
    assert!(toml::from_str::<GeneratorParams>("wobble = 1\n").is_err());
}

/// [`EvalOptions`] in JSON (as the eval report's `options`): the same keys, missing ones default.
#[test]
fn eval_options_json() {
    let opts = EvalOptions::default()
        .interior_margin(3.0)
        .background([1.0, 0.5, 0.25])
        .exemplar_step(2)
        .rim(RimParams { band: 3.0, ..Default::default() });
    let v = serde_json::to_value(&opts).unwrap();
    let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "background",
            "coherence",
            "depth_stretch",
            "exemplar_scale",
            "exemplar_step",
            "interior_margin",
            "motion",
            "paint_threshold",
            "patches",
            "rim",
            "temporal"
        ]
    );
    assert_eq!(v["interior_margin"], 3.0);
    assert_eq!(v["background"], serde_json::json!([1.0, 0.5, 0.25]));
    assert_eq!(v["exemplar_step"], 2);
    assert_eq!(v["exemplar_scale"], serde_json::Value::Null);
    assert_eq!(v["rim"]["band"], 3.0);
    assert_eq!(v["depth_stretch"], true);
    assert_eq!(serde_json::from_value::<EvalOptions>(v).unwrap(), opts);
    let partial: EvalOptions = serde_json::from_str(r#"{"paint_threshold": 0.2}"#).unwrap();
    assert_eq!(partial, EvalOptions::default().paint_threshold(0.2));
}

/// The setters set their fields and leave the others at the defaults.
#[test]
fn setters_set_their_fields() {
    let g = GuideParams::default()
        .blur_sigma(2.0)
        .mask_threshold(0.4)
        .time_blur_sigma(1.0)
        .flow_time_radius(5)
        .tangential_fit(false)
        .laplace_tolerance(1e-3);
    assert_eq!(
        (g.blur_sigma, g.mask_threshold, g.time_blur_sigma, g.flow_time_radius, g.tangential_fit, g.laplace_tolerance),
        (2.0, 0.4, 1.0, 5, false, 1e-3)
    );
    assert!(g.validate().is_ok());

    let e = EvalOptions::default().paint_threshold(0.2).exemplar_scale(0.5);
    assert_eq!((e.paint_threshold, e.exemplar_scale, e.exemplar_step), (0.2, Some(0.5), None));
    assert_eq!(e.interior_margin, EvalOptions::default().interior_margin);

    let s = SuiteOptions::default()
        .exemplars(["ink-rims", "blue-bloom"])
        .exemplar_dirs(["/tmp/exemplars"])
        .targets([TargetKind::Long])
        .identity(false)
        .scale(0.5)
        .frames(12)
        .long_frames(40)
        .window(10)
        .eval(e.clone())
        .sheets("/tmp/sheets")
        .jobs(1);
    assert_eq!(s.exemplars, ["ink-rims", "blue-bloom"]);
    assert_eq!(s.exemplar_dirs, [PathBuf::from("/tmp/exemplars")]);
    assert_eq!(s.targets, [TargetKind::Long]);
    assert_eq!((s.identity, s.scale, s.frames, s.long_frames, s.window, s.jobs), (false, 0.5, 12, 40, 10, 1));
    assert_eq!(s.eval, e);
    assert_eq!(s.sheets.as_deref(), Some(Path::new("/tmp/sheets")));
    assert!(s.validate().is_ok());
}
