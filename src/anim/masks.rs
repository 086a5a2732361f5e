//! Plain PNG mask sequences (the thesis's input): one directory, one region.

use super::{Animation, LoadOptions, Region, RegionFrame, RegionKind, RegionRenderer};
use crate::error::{Error, Result};
use crate::img::{self, Plane};
use std::path::{Path, PathBuf};

struct MaskSequence {
    files: Vec<PathBuf>,
    size: (usize, usize),
    scaled: (usize, usize),
}

impl RegionRenderer for MaskSequence {
    fn render(&self, _region: usize, frame: usize) -> Result<RegionFrame> {
        let path = &self.files[frame];
        let mut cov = img::load_gray(path)?;
        if cov.size() != self.size {
            return Err(Error::SizeMismatch {
                path: path.clone(),
                expected: (self.size.0 as u32, self.size.1 as u32),
                found: (cov.width() as u32, cov.height() as u32),
            });
        }
        if self.scaled != self.size {
            cov = img::resize_bilinear(&cov, self.scaled.0, self.scaled.1);
        }
        let fill = cov.map(|a| [1.0, 1.0, 1.0, a.clamp(0.0, 1.0)]);
        Ok(RegionFrame { fill, strokes: None, opacity_in_alpha: false })
    }
}

/// Loads PNG masks (`files` in order, as the directory, glob or single file `path` names them)
/// as a one-region animation at 24 fps. The region is named after the folder, or the file
/// without its extension; "masks" for a glob.
pub(super) fn load(path: &Path, files: Vec<PathBuf>, options: &LoadOptions) -> Result<Animation> {
    if files.len() > super::MAX_FRAMES {
        return Err(Error::Limit {
            path: path.to_path_buf(),
            what: "frame count".into(),
            value: files.len() as f64,
            limit: super::MAX_FRAMES as f64,
        });
    }
    let first: Plane<f32> = img::load_gray(&files[0])?;
    let size = first.size();
    let max = super::MAX_SIDE as usize;
    if size.0 > max || size.1 > max {
        return Err(Error::Limit {
            path: files[0].clone(),
            what: "mask side".into(),
            value: size.0.max(size.1) as f64,
            limit: max as f64,
        });
    }
    let scaled = super::scaled_canvas(path, size.0 as f32, size.1 as f32, options.scale)?;
    let scaled = (scaled.0 as usize, scaled.1 as usize);
    let name = if path.is_file() { path.file_stem() } else { path.file_name() };
    let name = name
        .map(|n| n.to_string_lossy().into_owned())
        .filter(|_| !crate::seq::is_glob(path))
        .unwrap_or_else(|| "masks".to_string());
    let region = Region {
        index: 1,
        name,
        kind: RegionKind::MaskSequence,
        visible: 0..files.len(),
        color: [1.0, 1.0, 1.0, 1.0],
        has_strokes: false,
        warnings: Vec::new(),
    };
    let frames = files.len();
    Ok(Animation::new(
        path.to_path_buf(),
        scaled.0 as u32,
        scaled.1 as u32,
        24.0,
        frames,
        vec![region],
        None,
        Vec::new(),
        Box::new(MaskSequence { files, size, scaled }),
    ))
}
