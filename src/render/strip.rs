//! A render of some of an image's tiles ([`TileStrip`]): whole 16×16 tiles of the image, side by
//! side in a strip `16·n × 16` pixels, seen through the image's camera. `--strategy auto`'s
//! pilots render one ([`crate::render::auto`]), so a pilot measures each candidate on a spread
//! quarter or half of the image at a quarter or half of the cost.
//!
//! Strip tile `j` shows the image's tile at `origins[j]`: the strip's pixel `(16j + x, y)` is the
//! image's pixel `origins[j] + (x, y)`, its camera ray and its sampler's pixel. A strip tile is
//! a tile of the render (the tile kernel's unit, and path reuse's blocks lie within it), so it
//! renders as that tile of the image does. Only whole tiles are taken (an image's partial
//! edge tiles never), so every strip pixel is an image pixel.

use super::TILE;
use crate::error::{Error, Result};
use glam::UVec2;

/// Some whole tiles of a `width × height` image, side by side (see the module doc).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TileStrip {
    /// The image's size.
    pub image: UVec2,
    /// The image's pixel at the top-left corner of each strip tile, in strip order.
    pub origins: Vec<UVec2>,
}

impl TileStrip {
    /// The whole tiles of a `width × height` image whose tile coordinates `(tx, ty)` satisfy
    /// `(tx + 2·ty) mod 4 = 0` (`stride` 4: a quarter, every fourth tile of a row, the rows
    /// shifted by two) or `(tx + ty) mod 2 = 0` (`stride` 2: a checkerboard, half), or all
    /// (`stride` 1); row by row.
    pub fn every(width: u32, height: u32, stride: u32) -> TileStrip {
        let (nx, ny) = (width / TILE, height / TILE);
        let keep = |tx: u32, ty: u32| match stride {
            0 | 1 => true,
            2 => (tx + ty).is_multiple_of(2),
            s => (tx + 2 * ty).is_multiple_of(s),
        };
        let origins = (0..ny)
            .flat_map(|ty| (0..nx).map(move |tx| (tx, ty)))
            .filter(|&(tx, ty)| keep(tx, ty))
            .map(|(tx, ty)| UVec2::new(tx * TILE, ty * TILE))
            .collect();
        TileStrip {
            image: UVec2::new(width, height),
            origins,
        }
    }

    /// The strip's size in pixels: `16·n × 16`.
    pub fn size(&self) -> (u32, u32) {
        (TILE * self.origins.len() as u32, TILE)
    }

    /// The image's pixel that the strip's pixel `p` shows.
    #[inline]
    pub fn image_pixel(&self, p: UVec2) -> UVec2 {
        self.origins[(p.x / TILE) as usize] + UVec2::new(p.x % TILE, p.y)
    }

    /// The image's row-major index of strip tile `t` (a strip's tile reuses its paths in the
    /// blocks the image's tile does: their grid's shift hashes the tile's index).
    pub fn image_tile(&self, t: u32) -> u32 {
        let o = self.origins[t as usize];
        o.y / TILE * self.image.x.div_ceil(TILE) + o.x / TILE
    }

    /// Whether a render of `width × height` can render this strip: its size, and tiles that
    /// lie whole within the image.
    pub fn check(&self, width: u32, height: u32) -> Result<()> {
        if self.origins.is_empty() || self.size() != (width, height) {
            return Err(Error::Settings(format!(
                "a strip of {} tiles is {}×{} pixels, not {width}×{height}",
                self.origins.len(),
                self.size().0,
                self.size().1
            )));
        }
        let outside = self.origins.iter().find(|o| {
            !(o.x.is_multiple_of(TILE) && o.y.is_multiple_of(TILE))
                || o.x + TILE > self.image.x
                || o.y + TILE > self.image.y
        });
        match outside {
            Some(o) => Err(Error::Settings(format!(
                "the strip's tile at {o} is not a whole tile of the {}×{} image",
                self.image.x, self.image.y
            ))),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The patterns take whole tiles only, in the shares they say, spread over the rows; and a
    /// strip pixel maps to its tile's image pixel.
    #[test]
    fn strips_take_whole_tiles_spread_over_the_image() {
        // 128 × 100: 8 × 6 whole tiles (the seventh row is partial)
        let all = TileStrip::every(128, 100, 1);
        assert_eq!(all.origins.len(), 48);
        let half = TileStrip::every(128, 100, 2);
        assert_eq!(half.origins.len(), 24);
        let quarter = TileStrip::every(128, 100, 4);
        assert_eq!(quarter.origins.len(), 12);
        for s in [&all, &half, &quarter] {
            s.check(s.size().0, s.size().1).unwrap();
            // every row of tiles is visited
            for ty in 0..6 {
                assert!(s.origins.iter().any(|o| o.y == ty * TILE), "row {ty}");
            }
        }
        // no two quarter tiles side by side in a row
        for w in quarter.origins.windows(2) {
            assert!(w[0].y != w[1].y || w[1].x - w[0].x >= 4 * TILE);
        }
        assert_eq!(
            quarter.image_pixel(UVec2::new(TILE + 3, 5)),
            quarter.origins[1] + UVec2::new(3, 5)
        );
        assert!(quarter.check(128, 16).is_err());
        let bad = TileStrip {
            image: UVec2::new(40, 40),
            origins: vec![UVec2::new(32, 0)],
        };
        assert!(bad.check(16, 16).is_err());
    }

    /// A strip renders exactly what the image's render puts in those tiles (the same camera
    /// rays, sampler streams and reuse blocks), with and without path reuse; only the strip's
    /// tiles are rendered (its rays are a share of the image's).
    #[test]
    fn a_strip_renders_the_images_tiles_bit_for_bit() {
        use crate::render::{render_passes, NoProgress, PassPlan, RenderSettings};
        use std::sync::Arc;
        let scene = crate::scene::load(std::path::Path::new("scenes/cornell-box")).unwrap();
        for reuse in [1, 4] {
            let image = RenderSettings {
                width: 64,
                height: 40, // a partial row of tiles the strip leaves out
                spp: 4,
                seed: 7,
                reuse,
                ..Default::default()
            };
            let whole = render_passes(&scene, &image, &PassPlan::default(), &NoProgress).unwrap();
            let strip = TileStrip::every(64, 40, 2);
            assert_eq!(strip.origins.len(), 4);
            let (w, h) = strip.size();
            let settings = RenderSettings {
                width: w,
                height: h,
                ..image.clone()
            };
            let plan = PassPlan {
                strip: Some(Arc::new(strip.clone())),
                ..Default::default()
            };
            let part = render_passes(&scene, &settings, &plan, &NoProgress).unwrap();
            for y in 0..h {
                for x in 0..w {
                    let p = strip.image_pixel(UVec2::new(x, y));
                    let a = part.film.pixel_sums((y * w + x) as usize);
                    let b = whole.film.pixel_sums((p.y * 64 + p.x) as usize);
                    assert_eq!(
                        a, b,
                        "reuse {reuse}: strip pixel ({x}, {y}), image pixel {p}"
                    );
                }
            }
            // the paths' camera rays (edge rays fall where the light's edges are)
            let paths = |r: &crate::integrator::RayCounts| r.camera - r.edge;
            let (a, b) = (paths(&part.stats.rays), paths(&whole.stats.rays));
            assert_eq!(a * 64 * 40, b * (w * h) as u64);
            // a strip of the wrong size is refused
            let wrong = RenderSettings {
                width: w + 1,
                ..settings
            };
            assert!(render_passes(&scene, &wrong, &plan, &NoProgress).is_err());
        }
    }
}
