//! The limits of what vrpt accepts, in one place for every reader and flag: magnitudes of scene
//! numbers, image sides, path lengths, and the memory an image needs, and the parsers of flag
//! values that hold them (seconds, exposure, shard, target). Depends on nothing of the
//! renderer, so the scene readers, the image reader and the renderer all take them from here.

use crate::error::{Error, Result};

/// The largest coordinate or emission a scene may hold: squares of it (lengths, sums of
/// squared radiance) stay finite in f32.
pub const MAX_MAGNITUDE: f32 = 1e15;

/// The largest image side, as `--width` and `--height` allow.
pub const MAX_SIDE: u32 = 65536;

/// The longest path, as `--max-depth` allows.
pub const MAX_DEPTH: u32 = 1024;

/// The longest time a render or a run may be given, in seconds (`--time-limit`,
/// `--equal-time`): 10⁷ s, about 116 days. Past it a value is refused (a float that large does
/// not even become a `Duration`).
pub const MAX_SECONDS: f64 = 1e7;

/// `seconds` as a `Duration`, or the error naming `flag`: a positive, finite number of seconds
/// at most [`MAX_SECONDS`].
pub fn duration(flag: &str, seconds: f64) -> Result<std::time::Duration> {
    if seconds > 0.0 && seconds <= MAX_SECONDS {
        Ok(std::time::Duration::from_secs_f64(seconds))
    } else {
        Err(Error::Settings(format!(
            "{flag} {seconds}: a time must be a positive number of seconds, at most {MAX_SECONDS:e}"
        )))
    }
}

/// The largest exposure, in stops either way (`--exposure`): 2⁶⁴ stays finite in f32.
pub const MAX_EXPOSURE: f32 = 64.0;

/// Bytes a render holds per pixel at its peak: the film's sums (2 × 24 B) and count (8 B), the
/// tiles' sums before they reach the film (56 B), and the written image's RGB, variance and
/// sample count (28 B) with the encoder's copy (≤ 28 B).
pub const BYTES_PER_PIXEL: u64 = 56 + 56 + 28 + 28;

/// Memory the system can still give, from `/proc/meminfo`'s `MemAvailable` (Linux), or the
/// bytes `VRPT_MEMORY_LIMIT` names where that is less (a share of a machine others use, or a
/// test of the refusals); `None` where neither is known.
fn available_memory() -> Option<u64> {
    let limit = std::env::var("VRPT_MEMORY_LIMIT")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok());
    let system = (|| {
        let info = std::fs::read_to_string("/proc/meminfo").ok()?;
        let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kib * 1024)
    })();
    match (system, limit) {
        (Some(s), Some(l)) => Some(s.min(l)),
        (s, l) => s.or(l),
    }
}

/// Bytes loading a scene holds per triangle at its peak, the BVH build's: the mesh read from
/// the file (108 B), the builder's input (36 B) and its own buffers (about 250 B: its binary
/// tree, and the collapse to 8-wide nodes, which keeps 7 decisions and costs for each node of
/// the binary tree). 383 MiB measured for a scene of a million triangles (process included).
pub const SCENE_PEAK_BYTES_PER_TRIANGLE: u64 = 400;

/// Bytes reading an OBJ file holds per byte of it at the peak of parsing: the text, and the
/// numbers and indices parsed from it (2.1 B per byte measured on a 72 MB file).
pub const OBJ_BYTES_PER_TEXT_BYTE: u64 = 3;

/// Bytes a render holds per pixel and replicate beyond [`BYTES_PER_PIXEL`]: each replicate's
/// weighted sum (24 B) and weight (8 B), and an adaptive round's film of it (56 B).
pub const BYTES_PER_REPLICATE_PIXEL: u64 = 32 + 56;

/// Bytes a texture or environment map holds per texel while it loads: the decoder's image
/// (at most 8 B: 16-bit RGBA), its RGBA8 copy (4 B) and the linear RGBA f32 texels kept for
/// rendering (16 B); an environment map's sampling tables (≤ 12 B) come after the decoder's
/// buffers are gone.
pub const TEXTURE_BYTES_PER_TEXEL: u64 = 28;

/// The most texels a texture or an environment map may declare: 2²⁸ (16384², about 7.5 GB
/// while it loads). A header past it is refused before anything is decoded.
pub const MAX_TEXELS: u64 = 1 << 28;

/// Refuse `need` bytes for `what` when the system cannot give them, before allocating any of
/// them (an allocation failure aborts the process, with no error line): the one memory check
/// every buffer that grows with the input passes.
pub fn check_bytes(what: &str, need: u64) -> Result<()> {
    match available_memory() {
        Some(have) if need > have => Err(Error::Settings(format!(
            "{what} needs about {:.1} GiB of memory; {:.1} GiB are available",
            need as f64 / (1u64 << 30) as f64,
            have as f64 / (1u64 << 30) as f64
        ))),
        _ => Ok(()),
    }
}

/// Refuse an image whose buffers cannot be allocated, before allocating any of them.
pub fn check_memory(width: u32, height: u32) -> Result<()> {
    check_render_memory(width, height, 1)
}

/// Refuse a render of `replicates` replicates whose buffers cannot be allocated: the image's
/// per-pixel bytes and each replicate's ([`BYTES_PER_REPLICATE_PIXEL`]).
pub fn check_render_memory(width: u32, height: u32, replicates: u32) -> Result<()> {
    let pixels = width as u64 * height as u64;
    let need = pixels * BYTES_PER_PIXEL + pixels * replicates as u64 * BYTES_PER_REPLICATE_PIXEL;
    let what = match replicates {
        0 | 1 => format!("a {width}x{height} image"),
        r => format!("a {width}x{height} image in {r} replicates"),
    };
    check_bytes(&what, need)
}

/// The most texels a PNG, JPEG or TGA file can hold per byte: deflate stops at 1032:1 and a
/// 1-bit PNG packs 8 pixels a byte (8256); JPEG's and TGA's run-length codes hold far fewer. A
/// header that declares more lies about its size.
pub const MAX_TEXELS_PER_BYTE: u64 = 8256;

/// Refuse a texture or environment map of `width`×`height` texels from its header: more than
/// [`MAX_TEXELS`], more than a file of `file_bytes` can hold ([`MAX_TEXELS_PER_BYTE`]; `None`
/// for formats this does not bound), or more memory than the system can give.
pub fn check_texels(
    width: u64,
    height: u64,
    file_bytes: Option<u64>,
) -> std::result::Result<(), String> {
    let texels = width.saturating_mul(height);
    if let Some(bytes) = file_bytes.filter(|&b| texels > MAX_TEXELS_PER_BYTE.saturating_mul(b)) {
        return Err(format!(
            "its header declares {width}x{height} texels, more than a {bytes}-byte file can hold"
        ));
    }
    if texels > MAX_TEXELS {
        return Err(format!(
            "its header declares {width}x{height} texels, more than the {MAX_TEXELS} vrpt reads"
        ));
    }
    check_bytes(
        &format!("a {width}x{height} texture"),
        texels * TEXTURE_BYTES_PER_TEXEL,
    )
    .map_err(|e| e.to_string())
}

/// The most worker threads a command takes.
pub const MAX_THREADS: usize = 1024;

// The values of flags, parsed in one place (clap value parsers): each refuses what the limits
// above refuse, with one line saying what it wanted.

/// A flag's positive, finite number of seconds.
pub fn parse_seconds(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x <= MAX_SECONDS => Ok(x),
        _ => Err(format!(
            "'{s}' is not a positive number of seconds up to {MAX_SECONDS:e}"
        )),
    }
}

/// An exposure in stops: a finite number within ±[`MAX_EXPOSURE`].
pub fn parse_exposure(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(x) if x.abs() <= MAX_EXPOSURE => Ok(x),
        _ => Err(format!(
            "'{s}' is not an exposure in stops from -{MAX_EXPOSURE} to {MAX_EXPOSURE}"
        )),
    }
}

/// `I/N` with `I < N` (a shard, as `--shard` takes it and metadata records it).
pub fn parse_shard(s: &str) -> std::result::Result<(u32, u32), String> {
    let bad = || format!("'{s}' is not a shard I/N (0 ≤ I < N, e.g. 0/4)");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let i: u32 = i.trim().parse().map_err(|_| bad())?;
    let n: u32 = n.trim().parse().map_err(|_| bad())?;
    if i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// A target relMSE: a positive finite number.
pub fn parse_target(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("'{s}' is not a positive relMSE")),
    }
}

/// A gain: a finite number ≥ 0.
pub fn parse_gain(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x >= 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("'{s}' is not a gain (a finite number ≥ 0)")),
    }
}

/// A count of worker threads, 1 to [`MAX_THREADS`].
pub fn parse_threads(s: &str) -> std::result::Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_THREADS).contains(&n) => Ok(n),
        _ => Err(format!(
            "'{s}' is not a thread count from 1 to {MAX_THREADS}"
        )),
    }
}
