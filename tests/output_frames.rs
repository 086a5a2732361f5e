//! PNG frame output.

use fluidymation::img::{Plane, load_rgba};
use fluidymation::output::{frame_path, prepare_dir, write_frame};

#[test]
fn frames_are_written_numbered_from_one() {
    let dir = std::env::temp_dir().join(format!("fm-output-frames-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    prepare_dir(&dir.join("out")).unwrap();
    let out = dir.join("out");
    let frame = Plane::from_fn(5, 3, |x, y| [x as f32 / 4.0, y as f32 / 2.0, 0.5, 1.0]);
    let first = write_frame(&out, 0, 3, &frame).unwrap();
    assert_eq!(first, out.join("0001.png"));
    assert_eq!(write_frame(&out, 2, 3, &frame).unwrap(), frame_path(&out, 2, 3));
    assert_eq!(load_rgba(&first).unwrap().get(4, 2), [1.0, 1.0, 128.0 / 255.0, 1.0]);
    let names: Vec<String> = {
        let mut v: Vec<String> =
            std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    };
    assert_eq!(names, ["0001.png", "0003.png"], "no temporary files are left");

    // A path below a regular file cannot become an output directory.
    let blocker = dir.join("file");
    std::fs::write(&blocker, b"x").unwrap();
    let err = prepare_dir(&blocker.join("sub")).unwrap_err().to_string();
    assert!(err.contains("file"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
