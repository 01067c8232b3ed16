//! Image textures of the MTL (`map_Kd`, `map_Ks`, `map_Ns`, `map_d`, `bump`/`map_Bump`, `norm`):
//! loading (PNG, JPEG, TGA through `image`; EXR through `exr`), decoding, and bilinear lookup.
//!
//! **Decoding.** 8-bit colour maps (`map_Kd`, `map_Ks`) are sRGB-encoded: each channel `c ∈
//! [0, 1]` becomes linear `c/12.92` for `c ≤ 0.04045`, else `((c + 0.055)/1.055)^2.4` (IEC
//! 61966-2-1). Scalar maps (`map_Ns`, `map_d`, bump heights) and normal maps are data, read
//! linearly (`c/255`). Alpha is always linear. EXR texels are linear already.
//!
//! **Lookup** at texture coordinates `(u, v)` (OBJ `vt`: (0, 0) is the image's bottom-left
//! corner) after the MTL's `-s` scale and `-o` offset, `uv' = uv·s + o`: the texel centres lie
//! at `((i + ½)/W, 1 − (j + ½)/H)` for column i and row j (row 0 at the top), and the four
//! around `uv'` are blended bilinearly, wrapping around every edge (repeat).
//!
//! A texture used by several materials, with the same decoding, is loaded once
//! ([`TextureSet::load`]).

use crate::error::{Error, Result};
use glam::{Vec2, Vec4};
use std::path::{Path, PathBuf};

/// How a file's texels are decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Decode {
    /// Colour: sRGB-encoded 8-bit channels decoded to linear.
    Srgb,
    /// Data: 8-bit channels read as `c/255`.
    Linear,
}

/// The sRGB decoding of one 8-bit channel value `c/255`.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A texture: linear RGBA texels, row-major, row 0 at the top of the image.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Vec<Vec4>,
    /// Whether the file had an alpha channel (`map_d` reads alpha when it has one).
    has_alpha: bool,
}

impl Texture {
    /// A texture of linear RGBA `texels` (row-major, row 0 at the top).
    pub fn new(width: u32, height: u32, texels: Vec<Vec4>, has_alpha: bool) -> Texture {
        assert!(width > 0 && height > 0 && texels.len() == (width * height) as usize);
        Texture {
            width,
            height,
            texels,
            has_alpha,
        }
    }

    /// 8-bit RGBA `bytes` decoded as `decode` says (alpha linear).
    pub fn from_rgba8(width: u32, height: u32, bytes: &[u8], decode: Decode, alpha: bool) -> Self {
        let f = |b: u8| match decode {
            Decode::Srgb => srgb_to_linear(b as f32 / 255.0),
            Decode::Linear => b as f32 / 255.0,
        };
        let texels = bytes
            .chunks_exact(4)
            .map(|p| Vec4::new(f(p[0]), f(p[1]), f(p[2]), p[3] as f32 / 255.0))
            .collect();
        Texture::new(width, height, texels, alpha)
    }

    /// Read `path`: EXR through `exr` (linear RGB, alpha 1), anything else through `image`.
    pub fn load(path: &Path, decode: Decode) -> Result<Texture> {
        let is_exr = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        if is_exr {
            let img = crate::image_io::read_exr(path)?;
            // read_exr refuses non-finite pixels; a texture's values are reflectances,
            // exponents, heights: never negative (they made negative radiance)
            if let Some(k) = img.pixels.iter().position(|p| p.min_element() < 0.0) {
                let w = img.width as usize;
                return Err(Error::ImageRead {
                    path: path.to_path_buf(),
                    message: format!(
                        "texel ({}, {}) is {}: a texture's values must not be negative",
                        k % w,
                        k / w,
                        img.pixels[k]
                    ),
                });
            }
            let texels = img.pixels.iter().map(|p| p.extend(1.0)).collect();
            return Ok(Texture::new(img.width, img.height, texels, false));
        }
        if !path.exists() {
            return Err(Error::NotFound {
                path: path.to_path_buf(),
            });
        }
        let err = |message: String| Error::ImageRead {
            path: path.to_path_buf(),
            message,
        };
        let open = || {
            image::ImageReader::open(path)
                .and_then(|r| r.with_guessed_format())
                .map_err(|e| err(e.to_string()))
        };
        // the header's size first: a few kilobytes can declare gigabytes of texels
        let (w, h) = open()?.into_dimensions().map_err(|e| err(e.to_string()))?;
        let bytes = std::fs::metadata(path)
            .map_err(|e| err(e.to_string()))?
            .len();
        crate::limits::check_texels(w as u64, h as u64, Some(bytes)).map_err(err)?;
        let mut reader = open()?;
        let mut limits = image::Limits::default();
        limits.max_alloc =
            Some(w as u64 * h as u64 * crate::limits::TEXTURE_BYTES_PER_TEXEL + (1 << 20));
        reader.limits(limits);
        let img = reader.decode().map_err(|e| err(e.to_string()))?;
        let alpha = img.color().has_alpha();
        let rgba = img.to_rgba8();
        let (w, h) = rgba.dimensions();
        if w == 0 || h == 0 {
            return Err(Error::ImageRead {
                path: path.to_path_buf(),
                message: "the image is empty".into(),
            });
        }
        Ok(Texture::from_rgba8(w, h, rgba.as_raw(), decode, alpha))
    }

    /// The size in texels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Bytes its texels take.
    pub fn bytes(&self) -> usize {
        self.texels.len() * std::mem::size_of::<Vec4>()
    }

    /// Whether the file had an alpha channel.
    pub fn has_alpha(&self) -> bool {
        self.has_alpha
    }

    /// The texel at column `x`, row `y` (row 0 at the top), each wrapped into range.
    #[inline]
    pub fn texel(&self, x: i64, y: i64) -> Vec4 {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        self.texels[y * self.width as usize + x]
    }

    /// The bilinear blend of the four texels around `uv` (OBJ convention, repeat wrapping).
    #[inline]
    pub fn bilinear(&self, uv: Vec2) -> Vec4 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = (1.0 - uv.y) * self.height as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return self.texel(0, 0);
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // wrap the base corner first, so huge coordinates keep their fraction's texels
        let (w, h) = (self.width as f32, self.height as f32);
        let (ix, iy) = (x0.rem_euclid(w) as i64, y0.rem_euclid(h) as i64);
        let a = self.texel(ix, iy).lerp(self.texel(ix + 1, iy), fx);
        let b = self.texel(ix, iy + 1).lerp(self.texel(ix + 1, iy + 1), fx);
        a.lerp(b, fy)
    }
}

/// A texture as a material uses it: which one, and the MTL's `-s` scale and `-o` offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into the scene's [`TextureSet`].
    pub index: u32,
    pub scale: Vec2,
    pub offset: Vec2,
}

impl TextureRef {
    /// The texture coordinates looked up for the surface's `uv`.
    #[inline]
    pub fn map(&self, uv: Vec2) -> Vec2 {
        uv * self.scale + self.offset
    }
}

/// The scene's textures, each file and decoding loaded once.
#[derive(Clone, Debug, Default)]
pub struct TextureSet {
    pub textures: Vec<Texture>,
    keys: Vec<(PathBuf, Decode)>,
}

impl TextureSet {
    /// The files of the textures loaded (canonical where they could be resolved).
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.keys.iter().map(|(p, _)| p.as_path())
    }

    /// The index of `path` decoded as `decode`, loading it at its first use.
    pub fn load(&mut self, path: &Path, decode: Decode) -> Result<u32> {
        let key = (
            path.canonicalize().unwrap_or_else(|_| path.to_path_buf()),
            decode,
        );
        if let Some(i) = self.keys.iter().position(|k| *k == key) {
            return Ok(i as u32);
        }
        let t = Texture::load(path, decode)?;
        self.textures.push(t);
        self.keys.push(key);
        Ok(self.textures.len() as u32 - 1)
    }

    /// Bytes all texels take.
    pub fn bytes(&self) -> usize {
        self.textures.iter().map(Texture::bytes).sum()
    }

    /// The texture of `r`.
    #[inline]
    pub fn get(&self, r: &TextureRef) -> &Texture {
        &self.textures[r.index as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// sRGB decoding at the ends, the linear segment, the knee and a mid value (hand-computed:
    /// 0.5 → ((0.5 + 0.055)/1.055)^2.4 = 0.214041).
    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-7);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        let t = Texture::from_rgba8(1, 1, &[255, 128, 0, 128], Decode::Srgb, true);
        let v = t.texel(0, 0);
        assert!((v.x - 1.0).abs() < 1e-6 && v.z == 0.0);
        assert!((v.y - srgb_to_linear(128.0 / 255.0)).abs() < 1e-6);
        assert!((v.w - 128.0 / 255.0).abs() < 1e-6, "alpha stays linear");
        let l = Texture::from_rgba8(1, 1, &[255, 128, 0, 255], Decode::Linear, false);
        assert!((l.texel(0, 0).y - 128.0 / 255.0).abs() < 1e-6);
    }

    /// A 2×2 texture of values 0, 1 (top row) and 2, 3 (bottom row): texel centres return their
    /// texel, the middle the mean, an edge midpoint the mean of the two texels across the wrap,
    /// and a corner of the image the mean of all four (repeat).
    #[test]
    fn bilinear_lookups_and_wrapping() {
        let px = [0.0f32, 1.0, 2.0, 3.0].map(Vec4::splat).to_vec();
        let t = Texture::new(2, 2, px, false);
        let at = |u: f32, v: f32| t.bilinear(Vec2::new(u, v)).x;
        // centres: column 0 at u = ¼, row 0 (top) at v = ¾
        assert_eq!(at(0.25, 0.75), 0.0);
        assert_eq!(at(0.75, 0.75), 1.0);
        assert_eq!(at(0.25, 0.25), 2.0);
        assert_eq!(at(0.75, 0.25), 3.0);
        assert_eq!(at(0.5, 0.5), 1.5);
        // u = 0 lies halfway between column 1 (wrapped) and column 0
        assert_eq!(at(0.0, 0.75), 0.5);
        // v = 1 (top edge) lies halfway between row 0 and row 1 (wrapped)
        assert_eq!(at(0.25, 1.0), 1.0);
        assert_eq!(at(0.0, 0.0), 1.5);
        assert_eq!(at(1.0, 1.0), 1.5);
        // repeat: whole periods away give the same value
        assert_eq!(at(3.25, -1.25), 0.0);
        assert_eq!(at(-0.25, 2.75), 1.0);
        // a quarter of the way from the centre of texel (0, 0) toward that of (1, 0)
        assert!((at(0.375, 0.75) - 0.25).abs() < 1e-6);
    }
}
