//! The HTML report of `compare`, `converge` and `diff` (`--report`): one self-contained page
//! (no network, no server) holding the reference and the renders as HDR data, tone-mapped in
//! the page with an exposure control, false-colour error views with their colour bar, an A/B
//! slider, pixel inspection, the sortable metrics tables, the settings that made the run, and
//! for `converge` the log-log plot.
//!
//! The page is the static template `report.html`; this module fills its one data tag with a
//! JSON payload:
//! - `images[]`: `{name, group, reference, rgb, stderr}`, where `rgb` and `stderr` (the
//!   per-pixel standard error of the mean, `√(variance of the mean)`, or null) are IEEE
//!   binary16 values, RGB interleaved, rows top to bottom (half floats keep 3 significant digits
//!   of HDR values at 6 bytes a pixel), stored as [`encode_halves`] says: the values'
//!   little-endian bytes split into two planes (all low bytes, then all high bytes: the high
//!   bytes, sign and exponent, repeat and compress well), zlib-compressed, base64. The page
//!   inflates them with the browser's own `DecompressionStream('deflate')`. The six presets on
//!   the 256×256 Cornell box: 2.7 MB instead of 7.4 MB for plain base64;
//! - `tables[]`: `{title, columns[{key, label, numeric}], rows[{key: value}], row_key}`, numbers
//!   exact (the page shows 4 significant digits and keeps the exact value in `data-value`);
//! - `settings`: `[[key, value]]`, how the report was made; `plot_svg`: the convergence plot;
//! - `summary` (compare): what the page opens on, [`Summary`]: the strategies ranked by MSE (or
//!   by efficiency for equal-time runs), the best one's image beside the reference.
//!
//! The payload holds no time or random identifier: the same data give the same file. Inside the
//! `<script>` tag, `</` is written `<\/` (the same string to JSON) so no value can close it.

use crate::analysis::experiments::{Comparison, Convergence, RegionRow};
use crate::error::{Error, Result};
use crate::image_io::{write_bytes, RgbImage};
use base64::Engine as _;
use glam::Vec3;
use serde::Serialize;
use std::io::{Read as _, Write as _};
use std::path::Path;

mod pages;

/// The page, with the data tag [`DATA_TAG`] that the payload replaces.
const TEMPLATE: &str = include_str!("report.html");
/// The template's empty data tag.
const DATA_TAG: &str = r#"<script type="application/json" id="vrpt-data">{}</script>"#;

/// One image of the report.
#[derive(Clone, Debug)]
pub struct ReportImage {
    /// Its label in the viewer.
    pub name: String,
    /// For `converge`: the spp the image belongs to ("16 spp"); empty otherwise.
    pub group: String,
    /// Whether it is the reference.
    pub reference: bool,
    /// Linear RGB, row-major.
    pub rgb: Vec<Vec3>,
    /// Per-pixel variance of the mean (the page shows its square root, the standard error).
    pub variance: Option<Vec<Vec3>>,
}

/// A column of a metrics table.
#[derive(Clone, Debug, Serialize)]
pub struct Column {
    /// The row field it shows.
    pub key: String,
    /// Its header.
    pub label: String,
    /// Whether it is a number (formatted and sortable as one).
    pub numeric: bool,
}

impl Column {
    /// A column of numbers.
    pub fn number(key: &str, label: &str) -> Column {
        Column {
            key: key.into(),
            label: label.into(),
            numeric: true,
        }
    }

    /// A column of text.
    pub fn text(key: &str, label: &str) -> Column {
        Column {
            key: key.into(),
            label: label.into(),
            numeric: false,
        }
    }
}

/// A metrics table: rows are JSON objects keyed by the columns' keys.
#[derive(Clone, Debug, Serialize)]
pub struct Table {
    /// Its heading.
    pub title: String,
    /// Its columns, in order.
    pub columns: Vec<Column>,
    /// Its rows, as JSON objects keyed by the columns' keys.
    pub rows: Vec<serde_json::Map<String, serde_json::Value>>,
    /// The column whose value names a row (unique within the table).
    pub row_key: String,
}

impl Table {
    /// A table of serializable rows (their fields named by the columns' keys; a NaN or
    /// infinite number becomes null, shown as "—").
    pub fn of<T: Serialize>(
        title: &str,
        columns: Vec<Column>,
        rows: &[T],
        row_key: &str,
    ) -> Result<Table> {
        let rows = rows
            .iter()
            .map(|r| match serde_json::to_value(r) {
                Ok(serde_json::Value::Object(m)) => Ok(m),
                _ => Err(Error::Settings("a report row is not an object".into())),
            })
            .collect::<Result<_>>()?;
        Ok(Table {
            title: title.into(),
            columns,
            rows,
            row_key: row_key.into(),
        })
    }
}

/// The answer a comparison report opens on: its strategies ranked by one column of its first
/// table, the best first, and the best one's image (shown beside the reference).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// The column ranked by: "mse" (equal spp: lower is better) or "efficiency" (equal time:
    /// higher is better).
    pub key: String,
    /// Its words, e.g. "MSE (lower is better)".
    pub label: String,
    /// The strategies, best first (rows whose value is not a number last, in table order).
    pub ranking: Vec<String>,
    /// The best strategy: the name of one of the report's images.
    pub best: String,
}

impl Summary {
    /// The rows of a comparison ranked by MSE (ascending), or with `by_efficiency` (equal-time
    /// runs: each run had the same time, so MSE ranks them too, but efficiency says it per
    /// second) by efficiency (descending).
    pub fn of(c: &Comparison, by_efficiency: bool) -> Summary {
        let value = |r: &crate::analysis::experiments::CompareRow| {
            if by_efficiency {
                -r.efficiency
            } else {
                r.mse
            }
        };
        let mut rows: Vec<_> = c.rows.iter().collect();
        rows.sort_by(|a, b| match (value(a).is_nan(), value(b).is_nan()) {
            (false, false) => value(a).total_cmp(&value(b)),
            (x, y) => x.cmp(&y),
        });
        let ranking: Vec<String> = rows.iter().map(|r| r.strategy.clone()).collect();
        let (key, label) = if by_efficiency {
            (
                "efficiency",
                "efficiency 1/(MSE·time), relative (higher is better)",
            )
        } else {
            ("mse", "MSE (lower is better)")
        };
        Summary {
            key: key.into(),
            label: label.into(),
            best: ranking.first().cloned().unwrap_or_default(),
            ranking,
        }
    }
}

/// Everything a report shows.
#[derive(Clone, Debug)]
pub struct Report {
    /// "compare", "converge" or "diff".
    pub kind: String,
    /// The page's title.
    pub title: String,
    /// The settings it was made with, as (name, value).
    pub settings: Vec<(String, String)>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The images of the viewer.
    pub images: Vec<ReportImage>,
    /// The metric tables.
    pub tables: Vec<Table>,
    /// A convergence plot, as SVG.
    pub plot_svg: Option<String>,
    /// What the page opens on, for a comparison.
    pub summary: Option<Summary>,
    /// The samples per pixel of adaptive runs, as PNG pictures (see [`SppMap`]).
    pub spp_maps: Vec<SppMap>,
}

/// What an adaptive run spent where: its samples per pixel as a false-colour PNG with its
/// colour bar ([`crate::analysis::maps::spp_map_png`]), base64 in the payload.
#[derive(Clone, Debug, Serialize)]
pub struct SppMap {
    /// The run's entry.
    pub name: String,
    /// The PNG, base64.
    pub png: String,
}

impl SppMap {
    /// The map of `samples` (`w × h`, row-major) under `name`.
    pub fn new(name: &str, samples: &[u32], (w, h): (u32, u32)) -> Result<SppMap> {
        let png = crate::analysis::maps::spp_map_png(samples, (w, h))?;
        Ok(SppMap {
            name: name.into(),
            png: base64::engine::general_purpose::STANDARD.encode(png),
        })
    }
}

#[derive(Serialize)]
struct ImagePayload<'a> {
    name: &'a str,
    group: &'a str,
    reference: bool,
    rgb: String,
    stderr: Option<String>,
}

#[derive(Serialize)]
struct Payload<'a> {
    kind: &'a str,
    title: &'a str,
    settings: &'a [(String, String)],
    width: u32,
    height: u32,
    images: Vec<ImagePayload<'a>>,
    tables: &'a [Table],
    plot_svg: Option<&'a str>,
    summary: Option<&'a Summary>,
    spp_maps: &'a [SppMap],
}

/// The payload's form of an image: its values as binary16, RGB interleaved, the little-endian
/// bytes split into a plane of low bytes and then one of high bytes, zlib (RFC 1950) at level 6,
/// base64. Deterministic: the same values give the same string.
pub fn encode_halves(values: impl Iterator<Item = Vec3>) -> String {
    let halves: Vec<u16> = values
        .flat_map(|v| v.to_array())
        .map(|c| half::f16::from_f32(c).to_bits())
        .collect();
    let mut planes = Vec::with_capacity(2 * halves.len());
    planes.extend(halves.iter().map(|h| (h & 0xff) as u8));
    planes.extend(halves.iter().map(|h| (h >> 8) as u8));
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    // writing to a Vec cannot fail
    z.write_all(&planes).expect("deflate into memory");
    let bytes = z.finish().expect("deflate into memory");
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// The inverse of [`encode_halves`]: the binary16 values as f32 (for tests and tools).
pub fn decode_halves(text: &str) -> Result<Vec<f32>> {
    let bad = |m: String| Error::Settings(format!("report image data: {m}"));
    let z = base64::engine::general_purpose::STANDARD
        .decode(text)
        .map_err(|e| bad(e.to_string()))?;
    let mut planes = Vec::new();
    flate2::read::ZlibDecoder::new(&z[..])
        .read_to_end(&mut planes)
        .map_err(|e| bad(e.to_string()))?;
    if planes.len() % 2 != 0 {
        return Err(bad("an odd number of bytes".into()));
    }
    let (lo, hi) = planes.split_at(planes.len() / 2);
    Ok(lo
        .iter()
        .zip(hi)
        .map(|(&l, &h)| half::f16::from_le_bytes([l, h]).to_f32())
        .collect())
}

impl Report {
    /// The page.
    pub fn to_html(&self) -> Result<String> {
        let n = (self.width * self.height) as usize;
        if let Some(i) = self
            .images
            .iter()
            .find(|i| i.rgb.len() != n || i.variance.as_ref().is_some_and(|v| v.len() != n))
        {
            return Err(Error::Settings(format!(
                "report: image '{}' is not {}x{}",
                i.name, self.width, self.height
            )));
        }
        let payload = Payload {
            kind: &self.kind,
            title: &self.title,
            settings: &self.settings,
            width: self.width,
            height: self.height,
            images: self
                .images
                .iter()
                .map(|i| ImagePayload {
                    name: &i.name,
                    group: &i.group,
                    reference: i.reference,
                    rgb: encode_halves(i.rgb.iter().copied()),
                    stderr: i
                        .variance
                        .as_ref()
                        .map(|v| encode_halves(v.iter().map(|x| x.max(Vec3::ZERO).powf(0.5)))),
                })
                .collect(),
            tables: &self.tables,
            plot_svg: self.plot_svg.as_deref(),
            summary: self.summary.as_ref(),
            spp_maps: &self.spp_maps,
        };
        let json = serde_json::to_string(&payload)
            .map_err(|e| Error::Settings(format!("report: {e}")))?
            .replace("</", "<\\/");
        let tag = format!(r#"<script type="application/json" id="vrpt-data">{json}</script>"#);
        match TEMPLATE.split_once(DATA_TAG) {
            Some((head, tail)) => Ok(format!("{head}{tag}{tail}")),
            None => Err(Error::Settings("report template lacks its data tag".into())),
        }
    }

    /// Write the page to `path` (through a temporary file).
    pub fn write(&self, path: &Path) -> Result<()> {
        write_bytes(path, self.to_html()?.as_bytes())
    }
}

/// A finite number as JSON, anything else as null (shown as "—").
pub fn number(x: f64) -> serde_json::Value {
    serde_json::Number::from_f64(x).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_round_trip_within_their_precision() {
        let v = [Vec3::new(0.0, 1.0, -2.5), Vec3::new(1e-3, 65504.0, 0.333)];
        let back = decode_halves(&encode_halves(v.iter().copied())).unwrap();
        assert_eq!(back.len(), 6);
        for (x, y) in v.iter().flat_map(|p| p.to_array()).zip(back) {
            assert!((x - y).abs() <= x.abs() * 2f32.powi(-11), "{x} {y}");
        }
        // the planes: 0x3c00 (1.0) is low byte 0x00, high byte 0x3c
        let one = encode_halves(std::iter::once(Vec3::ONE));
        let z = base64::engine::general_purpose::STANDARD
            .decode(one)
            .unwrap();
        let mut planes = Vec::new();
        flate2::read::ZlibDecoder::new(&z[..])
            .read_to_end(&mut planes)
            .unwrap();
        assert_eq!(planes, [0, 0, 0, 0x3c, 0x3c, 0x3c]);
        assert!(decode_halves("not base64!").is_err());
        assert!(decode_halves("AAAA").is_err());
    }

    #[test]
    fn the_payload_cannot_close_its_script_tag_and_the_page_is_deterministic() {
        let r = Report {
            kind: "diff".into(),
            title: "a </script><script>alert(1)</script> title".into(),
            settings: vec![("scene".into(), "x".into())],
            width: 1,
            height: 1,
            images: vec![ReportImage {
                name: "reference".into(),
                group: String::new(),
                reference: true,
                rgb: vec![Vec3::ONE],
                variance: None,
            }],
            tables: vec![],
            plot_svg: None,
            summary: None,
            spp_maps: vec![],
        };
        let html = r.to_html().unwrap();
        assert_eq!(
            html.matches("</script>").count(),
            TEMPLATE.matches("</script>").count()
        );
        assert!(html.contains(r#"a <\/script><script>alert(1)<\/script> title"#));
        assert_eq!(html, r.to_html().unwrap());
        let bad = Report {
            width: 2,
            ..r.clone()
        };
        assert!(bad.to_html().is_err());
    }

    /// The summary ranks by MSE at equal spp and by efficiency at equal time (which differ when
    /// the strategies' times differ), rows without a number last.
    #[test]
    fn the_summary_ranks_by_mse_or_by_efficiency() {
        use crate::analysis::experiments::CompareRow;
        let row = |name: &str, mse: f64, efficiency: f64| CompareRow {
            strategy: name.into(),
            runs: 2,
            spp: 16.0,
            seconds: 1.0,
            mse,
            rel_mse: 0.0,
            rmse: 0.0,
            mae: 0.0,
            variance: 0.0,
            est_mse: 0.0,
            est_rel_mse: 0.0,
            estimate: "per-sample".into(),
            bias_t: 0.0,
            bias_p: 1.0,
            mse_reduction: 1.0,
            efficiency,
        };
        let c = Comparison {
            rows: vec![
                row("a", 3.0, 1.0),
                row("b", f64::NAN, f64::NAN),
                row("c", 1.0, 2.0),
                row("d", 2.0, 5.0),
            ],
            regions: vec![],
            baseline: "a".into(),
            images: vec![],
            variances: vec![],
            spp_maps: vec![],
            reference_variance: None,
        };
        let s = Summary::of(&c, false);
        assert_eq!(
            (s.key.as_str(), s.ranking.join(",")),
            ("mse", "c,d,a,b".into())
        );
        assert_eq!(s.best, "c");
        let s = Summary::of(&c, true);
        assert_eq!(s.ranking.join(","), "d,c,a,b");
        assert_eq!(s.best, "d");
    }
}
