//! The library's `Render` builder: styles as values give the same frames as the same styles by
//! name, and the scale comes from the loaded animation.

use fluidymation::NoProgress;
use fluidymation::anim::{self, LoadOptions};
use fluidymation::exemplar::{self, SearchPath};
use fluidymation::render::{self, Background, Render, RenderOptions, Style};
use fluidymation::synth::Params;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn frames(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "png"))
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
        .collect()
}

#[test]
fn an_exemplar_in_memory_paints_as_the_same_exemplar_by_name() {
    let demo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/demo/waving.json");
    let a = anim::load(&demo, &LoadOptions::default().scale(0.25)).unwrap();
    assert_eq!(a.scale(), 0.25);
    let root = std::env::temp_dir().join(format!("fm-render-api-{}", std::process::id()));

    // The lower layer, styles by name.
    let mut opts = RenderOptions::new(root.join("named"), 0..2);
    opts.params = Params::builder().seed(3).build().unwrap();
    opts.default_style = Some(Style::None);
    opts.styles.push(("dress".into(), Style::named("ink-rims")));
    opts.background = "#fdfbf7".parse().unwrap();
    let named = render::render(&a, &opts, &NoProgress).unwrap();

    // The builder, the exemplar in memory.
    let ink = exemplar::find("ink-rims", &SearchPath::standard(&[])).unwrap();
    let built = Render::new(&a)
        .style_all(Style::None)
        .style("dress", Style::exemplar(ink))
        .background(Background::Color([253.0 / 255.0, 251.0 / 255.0, 247.0 / 255.0, 1.0]))
        .frames(0..2)
        .seed(3)
        .run(root.join("memory"), &NoProgress)
        .unwrap();

    assert_eq!(frames(&root.join("named")).len(), 2);
    assert!(frames(&root.join("named")) == frames(&root.join("memory")), "other bytes from the exemplar in memory");
    let dress = |s: &render::RenderSummary| s.layers.iter().find(|l| l.name == "dress").unwrap().exemplar.clone();
    assert_eq!(dress(&named).as_deref(), Some("ink-rims"));
    assert_eq!(dress(&built).as_deref(), Some("ink-rims"));
    assert!(built.layers.iter().filter(|l| l.name != "dress").all(|l| l.exemplar.is_none()));
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn an_unknown_layer_is_an_error_naming_the_layers() {
    let demo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/demo/waving.json");
    let a = anim::load(&demo, &LoadOptions::default().scale(0.25)).unwrap();
    let out = std::env::temp_dir().join(format!("fm-render-api-bad-{}", std::process::id()));
    let err = Render::new(&a).style("tail", "ink-rims").frames(0..1).run(&out, &NoProgress).unwrap_err().to_string();
    assert!(err.contains("tail") && err.contains("dress"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}
