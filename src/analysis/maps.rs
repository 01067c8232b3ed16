//! False-colour maps: an image's relative squared error against a reference, the samples an
//! adaptive render spent per pixel, `--roulette ears`'s factor at the first vertex, a guide's
//! directional densities and a warp's histograms, and the comparison grid (images over their
//! error maps). Each map is a log colour scale ([`crate::analysis::metrics::false_colour`])
//! with its colour bar and the bar's numeric range below it, drawn on an RGB8 `Canvas` and
//! written as PNG; text as in [`crate::analysis::plots`].

use crate::analysis::experiments::Comparison;
use crate::analysis::metrics::{colormap, false_colour, relative_error_map};
use crate::analysis::plots::{bitmap, register_font, FONT};
use crate::error::{Error, Result};
use crate::image_io::{tonemap, write_png_rgb8, RgbImage};
use plotters::prelude::*;
use std::path::Path;

/// Write the false-colour map of `image`'s per-pixel relative squared error against
/// `reference` (same size) as a PNG, with its colour bar and the bar's numeric range below it;
/// returns the range of the log colour scale.
pub fn write_error_map(path: &Path, image: &RgbImage, reference: &RgbImage) -> Result<(f64, f64)> {
    let map = relative_error_map(&image.pixels, &reference.pixels);
    let (lo, hi) = error_scale(&[&map]);
    let colours = false_colour(&map, lo, hi);
    let (w, h) = (image.width, image.height);
    let scale = (256 / w.max(h)).max(1);
    let mut c = Canvas::new((w * scale).max(420), h * scale + BAR_H);
    c.blit(0, 0, w, h, scale, &|k| colours[k]);
    c.colour_bar(0, h * scale, lo, hi, ERROR_TITLE)?;
    c.write(path)?;
    Ok((lo, hi))
}

/// Write the samples of each pixel (`w × h`, row-major) as a false-colour PNG on a log scale,
/// with its colour bar and range; returns the range. What an adaptive render spent where.
pub fn write_spp_map(path: &Path, samples: &[u32], (w, h): (u32, u32)) -> Result<(f64, f64)> {
    let (c, range) = spp_map(samples, (w, h))?;
    c.write(path)?;
    Ok(range)
}

/// [`write_spp_map`]'s picture as PNG bytes (for the HTML report).
pub fn spp_map_png(samples: &[u32], (w, h): (u32, u32)) -> Result<Vec<u8>> {
    let (c, _) = spp_map(samples, (w, h))?;
    let mut out = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(
        &mut out,
        &c.buf,
        c.w,
        c.h,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| Error::Settings(format!("spp map: {e}")))?;
    Ok(out.into_inner())
}

fn spp_map(samples: &[u32], (w, h): (u32, u32)) -> Result<(Canvas, (f64, f64))> {
    let map: Vec<f64> = samples.iter().map(|&n| n as f64).collect();
    let lo = map.iter().copied().fold(f64::INFINITY, f64::min).max(1.0);
    let hi = map.iter().copied().fold(0.0, f64::max).max(lo * 10.0);
    let c = value_map(&map, (w, h), (lo, hi), "samples per pixel, log scale")?;
    Ok((c, (lo, hi)))
}

/// A `w × h` map of positive values (row-major) in false colour on the log scale `lo..hi`,
/// over its colour bar titled `title`.
fn value_map(map: &[f64], (w, h): (u32, u32), (lo, hi): (f64, f64), title: &str) -> Result<Canvas> {
    let colours = false_colour(map, lo, hi);
    let scale = (256 / w.max(h)).max(1);
    let mut c = Canvas::new((w * scale).max(420), h * scale + BAR_H);
    c.blit(0, 0, w, h, scale, &|k| colours[k]);
    c.colour_bar(0, h * scale, lo, hi, title)?;
    Ok(c)
}

/// Write `--roulette ears`'s learned factor at each pixel's first vertex (row-major; 0 where
/// there is none, drawn as the scale's bottom) as a false-colour PNG on the log scale of the
/// factor's whole range, 0.05 to 20, so maps of different scenes compare.
pub fn write_ears_map(path: &Path, map: &[f32], (w, h): (u32, u32)) -> Result<()> {
    let (lo, hi) = crate::integrator::rrs::FACTOR_RANGE;
    let map: Vec<f64> = map.iter().map(|&n| n as f64).collect();
    let title = "EARS factor at the first vertex, log scale";
    value_map(&map, (w, h), (lo as f64, hi as f64), title)?.write(path)
}

/// Write two directional densities side by side as one false-colour PNG (log scale, shared):
/// `left` and `right` are `w × h` maps (row-major, row 0 at the top), each labelled, over one
/// colour bar titled `title`. Each map is drawn at 2× when it is small. Returns the scale.
pub fn write_density_pair(
    path: &Path,
    (left, right): (&[f64], &[f64]),
    (w, h): (u32, u32),
    (left_label, right_label): (&str, &str),
    title: &str,
) -> Result<(f64, f64)> {
    let max = left
        .iter()
        .chain(right)
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-30);
    // four decades below the largest value
    let (lo, hi) = (max * 1e-4, max);
    let (a, b) = (false_colour(left, lo, hi), false_colour(right, lo, hi));
    let scale = (256 / w.max(h)).clamp(1, 2);
    let gap = 16;
    let label_h = 22;
    let mut c = Canvas::new(2 * w * scale + gap, h * scale + label_h + BAR_H);
    c.blit(0, label_h, w, h, scale, &|k| a[k]);
    c.blit(w * scale + gap, label_h, w, h, scale, &|k| b[k]);
    c.text(&[
        (left_label.to_string(), 4, 4),
        (right_label.to_string(), w * scale + gap + 4, 4),
    ])?;
    c.colour_bar(0, h * scale + label_h, lo, hi, title)?;
    c.write(path)?;
    Ok((lo, hi))
}

/// Write rows of two maps each (left and right, `w × h`, row-major, row 0 drawn at the top),
/// each row on its own log scale (four decades below its largest value) and labelled, as one
/// PNG: a warp's histogram beside its integrated pdf, for `vrpt warptest`.
pub fn write_density_rows(
    path: &Path,
    rows: &[(String, &[f64], &[f64])],
    (w, h): (u32, u32),
) -> Result<()> {
    let scale = 3;
    let (gap, label_h) = (16, 22);
    let row_h = label_h + h * scale + 8;
    let mut c = Canvas::new(2 * w * scale + gap, row_h * rows.len().max(1) as u32);
    let mut labels = Vec::new();
    for (k, (label, left, right)) in rows.iter().enumerate() {
        let max = left
            .iter()
            .chain(right.iter())
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max)
            .max(1e-30);
        let (a, b) = (
            false_colour(left, max * 1e-4, max),
            false_colour(right, max * 1e-4, max),
        );
        let y0 = k as u32 * row_h;
        // bins run up in cosθ: draw the highest first, so the pole is at the top
        let flip = |v: &[[u8; 3]], i: usize| {
            let (x, y) = (i as u32 % w, i as u32 / w);
            v[((h - 1 - y) * w + x) as usize]
        };
        c.blit(0, y0 + label_h, w, h, scale, &|i| flip(&a, i));
        c.blit(w * scale + gap, y0 + label_h, w, h, scale, &|i| flip(&b, i));
        labels.push((label.clone(), 4, y0 + 4));
    }
    c.text(&labels)?;
    c.write(path)
}

/// What the error maps show.
const ERROR_TITLE: &str = "relative squared error (x−r)²/(r²+0.01), log scale";

/// Height of a colour bar with its labels.
const BAR_H: u32 = 48;

/// An RGB8 image being drawn: pixels blitted, colour bars and text.
struct Canvas {
    w: u32,
    h: u32,
    buf: Vec<u8>,
}

impl Canvas {
    fn new(w: u32, h: u32) -> Canvas {
        Canvas {
            w,
            h,
            buf: vec![255u8; (w * h * 3) as usize],
        }
    }

    /// Draw a `width × height` image at (x0, y0), each pixel `scale`² screen pixels.
    fn blit(
        &mut self,
        x0: u32,
        y0: u32,
        width: u32,
        height: u32,
        scale: u32,
        px: &dyn Fn(usize) -> [u8; 3],
    ) {
        for y in 0..height * scale {
            for x in 0..width * scale {
                let src = ((y / scale) * width + x / scale) as usize;
                let dst = (((y0 + y) * self.w + x0 + x) * 3) as usize;
                self.buf[dst..dst + 3].copy_from_slice(&px(src));
            }
        }
    }

    /// Write `lines` of text, the first at (x, y), 16 pixels apart.
    fn text(&mut self, lines: &[(String, u32, u32)]) -> Result<()> {
        register_font();
        let root = bitmap(&mut self.buf, (self.w, self.h)).into_drawing_area();
        let style = (FONT, 14).into_font().color(&BLACK);
        for (s, x, y) in lines {
            root.draw(&Text::new(s.clone(), (*x as i32, *y as i32), style.clone()))
                .map_err(|e| Error::Settings(format!("drawing text: {e}")))?;
        }
        root.present()
            .map_err(|e| Error::Settings(format!("drawing text: {e}")))
    }

    /// A colour bar across the canvas at height `y0`: the map from `lo` (left) to `hi` (right)
    /// on a log scale, its two ends and its middle labelled with their values, and a title.
    fn colour_bar(&mut self, x0: u32, y0: u32, lo: f64, hi: f64, title: &str) -> Result<()> {
        let (bx, bw) = (x0 + 8, self.w - x0 - 16);
        for x in 0..bw {
            let c = colormap(x as f64 / (bw - 1).max(1) as f64);
            for y in y0 + 4..y0 + 16 {
                let dst = ((y * self.w + bx + x) * 3) as usize;
                self.buf[dst..dst + 3].copy_from_slice(&c);
            }
        }
        let mid = (lo.max(1e-30).log10() + hi.max(lo * 10.0).log10()) / 2.0;
        let right = format!("{:.1e}", hi.max(lo * 10.0));
        self.text(&[
            (format!("{lo:.1e}"), bx, y0 + 18),
            (
                format!("{:.1e}", 10f64.powf(mid)),
                bx + bw / 2 - 24,
                y0 + 18,
            ),
            (right.clone(), bx + bw - 8 * right.len() as u32, y0 + 18),
            (title.to_string(), bx, y0 + 33),
        ])
    }

    fn write(self, path: &Path) -> Result<()> {
        write_png_rgb8(path, self.w, self.h, &self.buf)
    }
}

/// Write a comparison's grid as a PNG: one column per image, the reference first; the top row
/// holds the images (tone-mapped with `exposure`), the bottom row each strategy's error map
/// against the reference on one shared log scale, whose colour bar and range run below.
pub fn write_comparison_grid(
    path: &Path,
    c: &Comparison,
    reference: &RgbImage,
    exposure: f32,
) -> Result<()> {
    let maps: Vec<Vec<f64>> = c
        .images
        .iter()
        .map(|img| relative_error_map(img, &reference.pixels))
        .collect();
    let (lo, hi) = error_scale(&maps.iter().map(Vec::as_slice).collect::<Vec<_>>());
    let (w, h) = (reference.width, reference.height);
    let scale = (256 / w.max(h)).max(1);
    let (cw, ch, pad, label_h) = (w * scale, h * scale, 8u32, 40u32);
    let columns = 1 + c.rows.len() as u32;
    let gw = (pad + columns * (cw + pad)).max(480);
    let gh = label_h + ch + pad + ch + pad + BAR_H;
    let mut g = Canvas::new(gw, gh);
    let x_of = |col: u32| pad + col * (cw + pad);
    g.blit(x_of(0), label_h, w, h, scale, &|k| {
        tonemap(reference.pixels[k], exposure)
    });
    let mut labels = vec![("reference".to_string(), x_of(0), 4)];
    if let Ok(Some(m)) = crate::output::RenderMetadata::radiance(reference, Path::new("reference"))
    {
        labels.push((format!("{} spp", m.spp), x_of(0), 20));
    }
    labels.push((
        "error maps →".to_string(),
        x_of(0),
        label_h + ch + pad + ch / 2,
    ));
    for (i, ((row, img), map)) in c.rows.iter().zip(&c.images).zip(&maps).enumerate() {
        let x0 = x_of(i as u32 + 1);
        g.blit(x0, label_h, w, h, scale, &|k| tonemap(img[k], exposure));
        let colours = false_colour(map, lo, hi);
        g.blit(x0, label_h + ch + pad, w, h, scale, &|k| colours[k]);
        labels.push((row.strategy.clone(), x0, 4));
        labels.push((format!("{:.0} spp  MSE {:.2e}", row.spp, row.mse), x0, 20));
    }
    g.text(&labels)?;
    g.colour_bar(0, label_h + 2 * (ch + pad), lo, hi, ERROR_TITLE)?;
    g.write(path)
}

/// The range `[lo, hi]` an error-map colour scale spans: the 1st to 99.9th percentile of the
/// positive errors of all maps, so every map shares one scale.
pub fn error_scale(maps: &[&[f64]]) -> (f64, f64) {
    let mut v: Vec<f64> = maps
        .iter()
        .flat_map(|m| m.iter().copied())
        .filter(|x| *x > 0.0 && x.is_finite())
        .collect();
    if v.is_empty() {
        return (1e-6, 1.0);
    }
    v.sort_by(f64::total_cmp);
    let q = |f: f64| v[((v.len() - 1) as f64 * f) as usize];
    let (lo, hi) = (q(0.01), q(0.999));
    (lo, hi.max(lo * 10.0))
}
