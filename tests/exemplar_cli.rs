//! The `exemplar` commands, run as a user runs them.

use std::process::Command;

fn run(args: &[&str], home: &std::path::Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_fluidymation"))
        .args(args)
        .env("HOME", home)
        .env("XDG_DATA_HOME", home.join("data"))
        .env_remove("FLUIDYMATION_EXEMPLARS")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn list_show_generate_import() {
    let home = std::env::temp_dir().join(format!("fm-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&home);
    std::fs::create_dir_all(&home).unwrap();
    let (code, out, _) = run(&["exemplar", "list"], &home);
    assert_eq!(code, 0);
    assert!(out.contains("blue-bloom") && out.contains("bundled"), "{out}");

    let sheet = home.join("sheet.png");
    let (code, out, err) = run(&["exemplar", "show", "ink-rims", "-o", sheet.to_str().unwrap()], &home);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("border width") && sheet.is_file(), "{out}");

    let (code, _, err) = run(&["exemplar", "show", "no-such"], &home);
    assert_eq!(code, 1);
    assert!(err.contains("no exemplar named 'no-such'") && err.contains("blue-bloom"), "{err}");

    for (size, needle) in [("0x0", "16–2048"), ("100000x100000", "100000x100000"), ("12", "WIDTHxHEIGHT")] {
        let (code, _, err) = run(&["exemplar", "generate", "--name", "x", "--size", size], &home);
        assert_ne!(code, 0);
        assert!(err.contains(needle), "{size}: {err}");
    }

    // Generate into the user's folder (the default), then find it by name.
    let args =
        ["exemplar", "generate", "--name", "mine", "--size", "48x48", "--frames", "4", "--pigment", "rose", "-q"];
    let (code, _, err) = run(&args, &home);
    assert_eq!(code, 0, "{err}");
    assert!(home.join("data/fluidymation/exemplars/mine/exemplar.toml").is_file());
    let (code, out, _) = run(&["exemplar", "list"], &home);
    assert!(code == 0 && out.contains("mine") && out.contains("user folder"), "{out}");
    let (code, _, err) = run(&args, &home);
    assert_eq!(code, 1);
    assert!(err.contains("already exists"), "{err}");

    // Import its frames back.
    let frames = home.join("data/fluidymation/exemplars/mine/frames");
    let out_dir = home.join("imported");
    let (code, _, err) = run(
        &["exemplar", "import", frames.to_str().unwrap(), "--name", "back", "-o", out_dir.to_str().unwrap(), "-q"],
        &home,
    );
    assert_eq!(code, 0, "{err}");
    assert!(out_dir.join("back/masks/0004.png").is_file());
    let (code, out, _) = run(&["exemplar", "show", out_dir.join("back").to_str().unwrap()], &home);
    assert!(code == 0 && out.contains("imported"), "{out}");
    std::fs::remove_dir_all(&home).unwrap();
}

#[test]
fn a_name_that_hides_a_bundled_exemplar_is_warned_about() {
    let home = std::env::temp_dir().join(format!("fm-cli-shadow-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&home);
    std::fs::create_dir_all(&home).unwrap();
    let painted = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/demo/painted-0024.png");
    let (code, _, err) = run(&["exemplar", "import", painted, "--name", "blue-bloom"], &home);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("'blue-bloom' is also the name of a bundled exemplar") && err.contains("and the default style"),
        "{err}"
    );
    let (_, out, _) = run(&["exemplar", "list"], &home);
    assert!(out.contains("[hidden by an earlier one]"), "{out}");
    let (code, _, err) = run(&["exemplar", "import", painted, "--name", "my-swatch"], &home);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("bundled exemplar"), "{err}");
    let _ = std::fs::remove_dir_all(&home);
}
