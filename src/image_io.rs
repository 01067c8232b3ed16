//! Image files: EXR (linear RGB f32, with vrpt's metadata as string attributes, and optionally
//! the per-pixel variance of the mean as channels `variance.R/G/B`) and PNG (tone-mapped 8-bit
//! sRGB). Every write goes to a temporary file in the target folder which is
//! then renamed over the target, so an interrupted or failed write never destroys an older image.
//!
//! Tone mapping for PNG: `v · 2^exposure`, clamped to [0, 1], then the sRGB transfer function.

use crate::error::{Error, Result};
use exr::prelude::{
    self as exr_prelude, AttributeValue, ReadChannels, ReadLayers, Text, WritableImage,
};
use glam::Vec3;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The formats vrpt writes, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Exr,
    Png,
}

impl Format {
    /// The format for `path`'s extension, or an error naming the path.
    pub fn from_path(path: &Path) -> Result<Format> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("exr") => Ok(Format::Exr),
            Some("png") => Ok(Format::Png),
            _ => Err(Error::Write {
                path: path.to_path_buf(),
                message: "unknown image format (use .exr or .png)".into(),
            }),
        }
    }
}

/// An RGB image with metadata, as read back from an EXR.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    /// Row-major, top row first.
    pub pixels: Vec<Vec3>,
    /// The variance of each pixel's mean, when the file has `variance.R/G/B` channels.
    pub variance: Option<Vec<Vec3>>,
    /// The number of samples in each pixel's mean, when the file has a `samples` channel (u32).
    /// It differs from the metadata's spp where non-finite samples were dropped (and, with
    /// adaptive sampling, from pixel to pixel): merges weigh pixels by it.
    pub samples: Option<Vec<u32>>,
    /// The estimated variance of each pixel's mean from randomized replicates (see
    /// `vrpt::estimate`), when the file has `estimated_variance.R/G/B` channels.
    pub estimated_variance: Option<Vec<Vec3>>,
    /// vrpt's metadata (keys without the `vrpt.` prefix).
    pub metadata: BTreeMap<String, String>,
}

/// The sRGB transfer function of a linear value in [0, 1].
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Tone map a linear pixel to 8-bit sRGB.
#[inline]
pub fn tonemap(v: Vec3, exposure: f32) -> [u8; 3] {
    let s = 2f32.powf(exposure);
    let q = |c: f32| {
        let c = if c.is_finite() {
            (c * s).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (linear_to_srgb(c) * 255.0 + 0.5) as u8
    };
    [q(v.x), q(v.y), q(v.z)]
}

/// A temporary path beside `path`, for write-then-rename.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Temporary files being written: a process that must end at once (a second Ctrl-C) removes
/// them with [`remove_temp_files`] so it leaves nothing behind.
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Remove the temporary files of writes still under way (before the process exits mid-write;
/// the files they would replace are untouched).
pub fn remove_temp_files() {
    for p in pending().drain(..) {
        let _ = std::fs::remove_file(p);
    }
}

/// Write with `write` to a temporary file beside `path`, then rename it over `path`: an
/// interrupted or failed write leaves any older file intact.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), String>,
) -> Result<()> {
    let err = |message: String| Error::Write {
        path: path.to_path_buf(),
        message,
    };
    check_writable(path)?;
    let tmp = temp_path(path);
    pending().push(tmp.clone());
    let result = match write(&tmp) {
        Err(e) => Err(err(e)),
        Ok(()) => std::fs::rename(&tmp, path).map_err(|e| err(e.to_string())),
    };
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    pending().retain(|p| p != &tmp);
    result
}

/// The channels of the per-sample variance of the mean.
const VARIANCE_CHANNELS: [&str; 3] = ["variance.R", "variance.G", "variance.B"];
/// The channels of the replicates' estimated variance of the mean.
const ESTIMATE_CHANNELS: [&str; 3] = [
    "estimated_variance.R",
    "estimated_variance.G",
    "estimated_variance.B",
];

/// Write `image` as a linear RGB f32 EXR: channels `R`, `G`, `B`, and where the image has them
/// `variance.R/G/B` and `estimated_variance.R/G/B` (f32) and `samples` (u32), with its metadata stored as string attributes
/// named `vrpt.KEY`. Through a temporary file (see [`write_atomically`]).
pub fn write_exr(path: &Path, image: &RgbImage) -> Result<()> {
    use exr_prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Layer, LayerAttributes};
    let n = image.width as usize * image.height as usize;
    assert_eq!(image.pixels.len(), n);
    let f32s = |name: &str, v: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(v));
    let plane = |v: &[Vec3], c: usize| v.iter().map(|p| p[c]).collect::<Vec<f32>>();
    let mut list = exr_prelude::SmallVec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        list.push(f32s(name, plane(&image.pixels, c)));
    }
    for (var, names) in [
        (&image.variance, VARIANCE_CHANNELS),
        (&image.estimated_variance, ESTIMATE_CHANNELS),
    ] {
        if let Some(var) = var {
            assert_eq!(var.len(), n);
            for (c, name) in names.into_iter().enumerate() {
                list.push(f32s(name, plane(var, c)));
            }
        }
    }
    if let Some(samples) = &image.samples {
        assert_eq!(samples.len(), n);
        list.push(AnyChannel::new(
            "samples",
            FlatSamples::U32(samples.clone()),
        ));
    }
    let mut attributes = LayerAttributes::default();
    for (k, v) in &image.metadata {
        attributes.other.insert(
            Text::from(format!("vrpt.{k}").as_str()),
            AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    let layer = Layer::new(
        (image.width as usize, image.height as usize),
        attributes,
        Encoding::default(),
        AnyChannels::sort(list),
    );
    let exr = exr_prelude::Image::from_layer(layer);
    write_atomically(path, |tmp| {
        exr.write().to_file(tmp).map_err(|e| e.to_string())
    })
}

/// Write `pixels` as a tone-mapped 8-bit sRGB PNG.
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Vec3],
    exposure: f32,
) -> Result<()> {
    assert_eq!(pixels.len(), width as usize * height as usize);
    let bytes: Vec<u8> = pixels.iter().flat_map(|&v| tonemap(v, exposure)).collect();
    write_png_rgb8(path, width, height, &bytes)
}

/// Write 8-bit RGB bytes (row-major, `width × height × 3`) as a PNG, as they are.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    assert_eq!(rgb.len(), width as usize * height as usize * 3);
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            rgb,
            width,
            height,
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())
    })
}

/// Write `bytes` to `path` through a temporary file (see [`write_atomically`]).
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| e.to_string())
    })
}

/// Check before a long job that `path` can be written: its folder exists and it is not a
/// folder.
pub fn check_writable(path: &Path) -> Result<()> {
    let err = |message: String| Error::Write {
        path: path.to_path_buf(),
        message,
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(err(format!("folder {} does not exist", dir.display())));
        }
    }
    if path.is_dir() {
        return Err(err("is a folder".into()));
    }
    Ok(())
}

/// What `path` names, for telling whether two paths are one file: canonical where it exists
/// (symlinks, `./` and `..` resolved), else its folder's canonical path joined with its name.
pub(crate) fn file_key(path: &Path) -> PathBuf {
    if let Ok(c) = path.canonicalize() {
        return c;
    }
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    match (dir.canonicalize(), path.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => path.to_path_buf(),
    }
}

/// A path with the flag (or argument) that named it, for errors: `("-o", path)`.
pub type NamedPath<'a> = (&'a str, &'a Path);

/// Refuse, before any work, a command whose outputs name one file twice or name one of its
/// inputs: `outputs` and `inputs` are `(flag, path)` pairs, compared by canonical path, and the
/// error names both flags. (Every output is written by renaming a temporary file over it, so a
/// clash would silently destroy the other file.)
pub fn check_outputs(outputs: &[NamedPath], inputs: &[NamedPath]) -> Result<()> {
    let outs: Vec<(&str, &Path, PathBuf)> =
        outputs.iter().map(|&(f, p)| (f, p, file_key(p))).collect();
    let ins: Vec<(&str, &Path, PathBuf)> =
        inputs.iter().map(|&(f, p)| (f, p, file_key(p))).collect();
    for (k, (flag, path, key)) in outs.iter().enumerate() {
        if let Some((f, p, _)) = outs[..k].iter().find(|o| o.2 == *key) {
            return Err(Error::Settings(format!(
                "{f} {} and {flag} {} are the same file: one would overwrite the other",
                p.display(),
                path.display()
            )));
        }
        if let Some((f, p, _)) = ins.iter().find(|i| i.2 == *key) {
            return Err(Error::Settings(format!(
                "{flag} {} is the input {f} {}: writing it would destroy it",
                path.display(),
                p.display()
            )));
        }
    }
    Ok(())
}

/// Check that `path` names an image format vrpt writes and can be written; returns the format.
pub fn check_image_path(path: &Path) -> Result<Format> {
    let f = Format::from_path(path)?;
    check_writable(path)?;
    Ok(f)
}

/// Refuse, from its header alone, an EXR whose declared size cannot be real or allocated: more
/// pixels than [`MAX_PIXELS_PER_BYTE`] per byte of file (no EXR compression packs more: deflate
/// stops at 1032:1, that is under 200 pixels per byte at 6 bytes per pixel) or more than the
/// memory available.
fn check_exr_size(path: &Path) -> Result<()> {
    let err = |message: String| Error::ImageRead {
        path: path.to_path_buf(),
        message,
    };
    let bytes = std::fs::metadata(path)
        .map_err(|e| err(e.to_string()))?
        .len();
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| err(e.to_string()))?;
    for h in meta.headers.iter() {
        let (w, hgt) = (h.layer_size.width() as u64, h.layer_size.height() as u64);
        let pixels = w.saturating_mul(hgt);
        if pixels > MAX_PIXELS_PER_BYTE.saturating_mul(bytes) {
            return Err(err(format!(
                "its header declares {w}x{hgt} pixels, more than a {bytes}-byte file can hold"
            )));
        }
        crate::limits::check_memory(
            w.min(u32::MAX as u64) as u32,
            hgt.min(u32::MAX as u64) as u32,
        )
        .map_err(|e| err(e.to_string()))?;
    }
    Ok(())
}

/// The most pixels an EXR may declare per byte of its file (see [`read_exr`]).
pub const MAX_PIXELS_PER_BYTE: u64 = 1024;

/// Read the first RGB layer of an EXR, its `variance.*` and `samples` channels if any, and
/// vrpt's metadata. Every pixel must be a finite colour, every variance finite and
/// non-negative, every sample count a whole number (any other channel is ignored).
pub fn read_exr(path: &Path) -> Result<RgbImage> {
    if !path.exists() {
        return Err(Error::NotFound {
            path: path.to_path_buf(),
        });
    }
    check_exr_size(path)?;
    let err = |message: String| Error::ImageRead {
        path: path.to_path_buf(),
        message,
    };
    let image = exr_prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| err(e.to_string()))?;
    let layer = &image.layer_data;
    let size = layer.size;
    let mut metadata = BTreeMap::new();
    for (k, v) in &layer.attributes.other {
        if let (Some(key), AttributeValue::Text(t)) = (k.to_string().strip_prefix("vrpt."), v) {
            metadata.insert(key.to_string(), t.to_string());
        }
    }
    let channels = ExrChannels {
        path,
        list: &layer.channel_data.list,
        width: size.width(),
        height: size.height(),
    };
    let pixels = channels
        .rgb(["R", "G", "B"])
        .ok_or_else(|| err("has no R, G and B channels".into()))?;
    if let Some(i) = pixels.iter().position(|p| !p.is_finite()) {
        let (x, y) = channels.at(i);
        return Err(err(format!("pixel ({x}, {y}) is not a finite colour")));
    }
    Ok(RgbImage {
        width: channels.width as u32,
        height: channels.height as u32,
        pixels,
        variance: channels.variances(VARIANCE_CHANNELS, "variance")?,
        estimated_variance: channels.variances(ESTIMATE_CHANNELS, "estimated variance")?,
        samples: channels.samples()?,
        metadata,
    })
}

/// The channels of the EXR layer [`read_exr`] reads, its size, and its file (for errors).
struct ExrChannels<'a> {
    path: &'a Path,
    list: &'a [exr_prelude::AnyChannel<exr_prelude::FlatSamples>],
    width: usize,
    height: usize,
}

impl ExrChannels<'_> {
    /// An error reading the file.
    fn err(&self, message: String) -> Error {
        Error::ImageRead {
            path: self.path.to_path_buf(),
            message,
        }
    }

    /// The pixel `(x, y)` of row-major index `i`.
    fn at(&self, i: usize) -> (usize, usize) {
        (i % self.width.max(1), i / self.width.max(1))
    }

    /// The samples of the channel `name`, if the layer has it.
    fn find(&self, name: &str) -> Option<&exr_prelude::FlatSamples> {
        self.list
            .iter()
            .find(|c| c.name == *name)
            .map(|c| &c.sample_data)
    }

    /// The three channels `names` as one colour per pixel, if the layer has all three.
    fn rgb(&self, names: [&str; 3]) -> Option<Vec<Vec3>> {
        let planes: Vec<Vec<f32>> = names
            .iter()
            .map(|n| self.find(n).map(|d| d.values_as_f32().collect()))
            .collect::<Option<_>>()?;
        Some(
            (0..self.width * self.height)
                .map(|i| Vec3::new(planes[0][i], planes[1][i], planes[2][i]))
                .collect(),
        )
    }

    /// The variances in the channels `names` (called `what` in errors), if the layer has them:
    /// an error where it has only some of the three or a value is negative or not finite.
    fn variances(&self, names: [&str; 3], what: &str) -> Result<Option<Vec<Vec3>>> {
        let v = self.rgb(names);
        if v.is_none() && names.iter().any(|n| self.find(n).is_some()) {
            return Err(self.err(format!(
                "has some of the channels {} but not all",
                names.join(", ")
            )));
        }
        if let Some(i) = v.as_ref().and_then(|v| {
            v.iter()
                .position(|p| !(p.is_finite() && p.min_element() >= 0.0))
        }) {
            let (x, y) = self.at(i);
            return Err(self.err(format!(
                "the {what} of pixel ({x}, {y}) is not a finite non-negative number"
            )));
        }
        Ok(v)
    }

    /// The `samples` channel's counts, if the layer has it: an error where a count stored as a
    /// float is not a whole number a u32 holds.
    fn samples(&self) -> Result<Option<Vec<u32>>> {
        use exr_prelude::FlatSamples;
        Ok(match self.find("samples") {
            None => None,
            Some(FlatSamples::U32(v)) => Some(v.clone()),
            Some(other) => {
                let v: Vec<f32> = other.values_as_f32().collect();
                if let Some(i) = v
                    .iter()
                    .position(|&c| !(c >= 0.0 && c <= u32::MAX as f32 && c.fract() == 0.0))
                {
                    let (x, y) = self.at(i);
                    return Err(self.err(format!(
                        "the sample count of pixel ({x}, {y}) is not a whole number"
                    )));
                }
                Some(v.iter().map(|&c| c as u32).collect())
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints_and_tonemap() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert_eq!(tonemap(Vec3::new(0.0, 1.0, 4.0), 0.0), [0, 255, 255]);
        assert_eq!(
            tonemap(Vec3::splat(0.25), 1.0),
            tonemap(Vec3::splat(0.5), 0.0)
        );
        assert_eq!(tonemap(Vec3::splat(f32::NAN), 0.0), [0, 0, 0]);
    }

    #[test]
    fn exr_round_trip_with_metadata() {
        let dir = std::env::temp_dir().join(format!("vrpt-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.exr");
        let px: Vec<Vec3> = (0..6).map(|i| Vec3::new(i as f32, 0.5, -1.0)).collect();
        let mut meta = BTreeMap::new();
        meta.insert("spp".to_string(), "64".to_string());
        let mut image = RgbImage {
            width: 3,
            height: 2,
            pixels: px.clone(),
            metadata: meta,
            ..RgbImage::default()
        };
        write_exr(&path, &image).unwrap();
        let img = read_exr(&path).unwrap();
        assert_eq!(img, image);
        assert_eq!(img.metadata.get("spp").map(String::as_str), Some("64"));
        image.variance = Some((0..6).map(|i| Vec3::splat(i as f32 * 0.25)).collect());
        image.samples = Some(vec![0, 1, 7, 64, 1 << 30, u32::MAX]);
        write_exr(&path, &image).unwrap();
        assert_eq!(read_exr(&path).unwrap(), image);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
