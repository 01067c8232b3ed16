//! `vrpt warptest`: every warp vrpt draws directions with, tested as Mitsuba's warp test does.
//! `N` directions from independent uniform `u` are binned in `cosθ × φ` about a pole, beside the
//! warp's pdf integrated over each bin (a midpoint rule); Pearson's chi-square over the bins
//! (those expecting fewer than 5 pooled) gives a p-value, and `∫ pdf dω` over the sphere, which
//! must be 1, is computed by the same quadrature ([`crate::stats::chi2_directions_binned`], the
//! harness the tests use). The warps: uniform and cosine hemispheres, Phong lobes (exponents 10
//! and 100), a spherical triangle and a spherical rectangle seen from a point (uniform in solid
//! angle, and warped by the receiver's cosine: the `solid-angle` and `projected` light points,
//! through the light sampler itself), and an environment map sampled by luminance (a 64×32 sky
//! with a sun, built here), a triangle by area (the `area` light points: pdf per solid angle
//! `dist²/(A cosθ)`), and a learned guide's leaf: the directional quadtree of a path
//! guide trained here on a known radiance (a dim sky, a bright lobe and a window, four
//! iterations of recorded directions through the guide's own `add_records` and
//! `finish_iteration`), sampled by hierarchical warping ([`crate::guiding::DTree::sample`])
//! against its piecewise-constant pdf. `--pdf-scale` multiplies every pdf, to see a wrong one
//! caught.

use crate::environment::EnvMap;
use crate::error::Result;
use crate::lights::{Emitter, LightChoice, LightPoints, Lights};
use crate::sampler::{IndependentSampler, Sampler};
use crate::sampling::{
    cosine_hemisphere_pdf, phong_lobe_pdf, sample_cosine_hemisphere, sample_phong_lobe,
    sample_uniform_hemisphere, uniform_hemisphere_pdf,
};
use crate::stats::{chi2_directions_binned, Chi2Binning};
use glam::{UVec2, Vec2, Vec3};
use std::path::PathBuf;

/// What to test (the flags of `vrpt warptest`).
#[derive(Clone, Debug, clap::Args)]
pub struct WarptestRequest {
    /// Directions drawn per warp.
    #[arg(long, default_value_t = 200_000, value_parser = clap::value_parser!(u32).range(1000..=100_000_000))]
    pub n: u32,
    /// Seed of the uniform points.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// A factor on every pdf (1: the warps' own); 1.05 shows a 5% error caught.
    #[arg(long, default_value_t = 1.0, value_parser = parse_scale)]
    pub pdf_scale: f32,
    /// Histograms beside integrated pdfs, one row per warp (.png).
    #[arg(short = 'o', long, value_name = "PNG")]
    pub output: Option<PathBuf>,
    /// The numbers as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

fn parse_scale(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(x) if x > 0.0 && x <= 100.0 => Ok(x),
        _ => Err(format!("'{s}' is not a factor in (0, 100]")),
    }
}

/// One warp's test.
#[derive(Clone, Debug, serde::Serialize)]
pub struct WarpRow {
    pub warp: String,
    pub chi2: f64,
    pub dof: usize,
    pub p_value: f64,
    pub pdf_integral: f64,
    /// Observed and expected counts per bin (`z_bins × phi_bins`), for the picture.
    #[serde(skip)]
    pub bins: (Vec<f64>, Vec<f64>, (u32, u32)),
}

/// A warp: its name, `sample(u)`, its pdf per solid angle, and the binning that resolves it.
type Warp = (
    String,
    Box<dyn Fn(Vec2) -> Option<Vec3>>,
    Box<dyn Fn(Vec3) -> f32>,
    Chi2Binning,
);

/// The warps vrpt has, in a fixed order (each row's seed is its place in the list).
fn warps() -> Vec<Warp> {
    let mut v = hemisphere_warps();
    // a triangle and a rectangle in the plane z = 0, seen from above
    let p = Vec3::new(0.1, 0.2, 1.0);
    let normal = Vec3::new(0.3, 0.0, -1.0).normalize();
    let tri = [
        Vec3::new(-1.0, -0.8, 0.0),
        Vec3::new(1.2, -0.5, 0.0),
        Vec3::new(0.1, 1.0, 0.0),
    ];
    let rect = [
        Vec3::new(-1.0, -0.8, 0.0),
        Vec3::new(1.0, -0.8, 0.0),
        Vec3::new(1.0, 0.9, 0.0),
        Vec3::new(-1.0, 0.9, 0.0),
    ];
    let le = Vec3::splat(5.0);
    for (shape, corners) in [
        ("spherical triangle", &tri[..]),
        ("spherical rectangle", &rect[..]),
    ] {
        // wound so that the light faces +z, toward p
        let emitters = if corners.len() == 3 {
            vec![Emitter::triangle(
                0,
                [corners[0], corners[1], corners[2]],
                le,
            )]
        } else {
            vec![
                Emitter::triangle(0, [corners[0], corners[1], corners[2]], le),
                Emitter::triangle(1, [corners[0], corners[2], corners[3]], le),
            ]
        };
        for points in [LightPoints::SolidAngle, LightPoints::Projected] {
            v.push(light_warp(
                format!("{shape} ({points})"),
                &emitters,
                corners,
                points,
                (p, normal),
            ));
        }
    }
    v.push(environment_warp());
    // the triangle by area (the `area` light points): uniform on the triangle, so per solid
    // angle `dist² / (A |cos θ_light|)`; last, so that the rows before keep their seeds
    v.push(light_warp(
        "triangle by area".into(),
        &[Emitter::triangle(0, tri, le)],
        &tri,
        LightPoints::Area,
        (p, normal),
    ));
    v.push(guide_warp());
    v
}

/// The warps of the BSDFs about +z: uniform and cosine hemispheres, Phong lobes of exponents 10
/// and 100 (binned from where the lobe's pdf falls to 1e-3 of its peak).
fn hemisphere_warps() -> Vec<Warp> {
    let mut v: Vec<Warp> = vec![
        (
            "uniform hemisphere".into(),
            Box::new(|u| Some(sample_uniform_hemisphere(u))),
            Box::new(|w: Vec3| {
                if w.z > 0.0 {
                    uniform_hemisphere_pdf()
                } else {
                    0.0
                }
            }),
            Chi2Binning::default(),
        ),
        (
            "cosine hemisphere".into(),
            Box::new(|u| Some(sample_cosine_hemisphere(u))),
            Box::new(|w: Vec3| cosine_hemisphere_pdf(w.z)),
            Chi2Binning::default(),
        ),
    ];
    for n in [10.0f32, 100.0] {
        v.push((
            format!("Phong lobe, exponent {n}"),
            Box::new(move |u| Some(sample_phong_lobe(n, u))),
            Box::new(move |w: Vec3| phong_lobe_pdf(n, w.z)),
            Chi2Binning {
                z_lo: 1e-3f32.powf(1.0 / (n + 1.0)),
                ..Default::default()
            },
        ));
    }
    v
}

/// The environment map's warp: a 64×32 sky with a sun, sampled by luminance × sinθ.
fn environment_warp() -> Warp {
    let (w, h) = (64u32, 32u32);
    let sky: Vec<Vec3> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let sun = if (x - 40.0).abs() < 1.5 && (y - 9.0).abs() < 1.5 {
                400.0
            } else {
                0.0
            };
            Vec3::new(0.3, 0.5, 1.0) * (1.0 - y / h as f32) + Vec3::splat(sun)
        })
        .collect();
    let map = std::rc::Rc::new(EnvMap::new(w, h, &sky, 0.0, 1.0).expect("the sky is valid"));
    let (m1, m2) = (map.clone(), map);
    (
        "environment map (luminance)".into(),
        Box::new(move |u| m1.sample(u).map(|s| s.0)),
        Box::new(move |d: Vec3| m2.pdf(d)),
        // the pdf is constant on texels, which the bins do not follow: fine quadrature
        Chi2Binning {
            pole: Vec3::Y,
            z_bins: 64,
            phi_bins: 128,
            quadrature: 24,
            ..Default::default()
        },
    )
}

/// The warp of a learned guide's leaf ([`trained_guide_leaf`]): hierarchical sampling of its
/// quadtree beside its piecewise-constant pdf.
fn guide_warp() -> Warp {
    let guide = std::rc::Rc::new(trained_guide_leaf());
    let (g1, g2) = (guide.clone(), guide);
    (
        "guide leaf (learned quadtree)".into(),
        Box::new(move |u| Some(g1.sample(u))),
        Box::new(move |d: Vec3| g2.pdf(d)),
        // bins uniform in cosθ and φ about +z are the quadtree's canonical cells (32 × 32: its
        // first five levels; few enough that a 5% pdf error moves the statistic ~10 standard
        // deviations); the quadrature's 32 points per side resolve five levels more
        Chi2Binning {
            z_bins: 32,
            phi_bins: 32,
            quadrature: 32,
            ..Default::default()
        },
    )
}

/// The warp of a light's points seen from `p` (shading normal `normal`): the light sampler's
/// directions toward `emitters` (a light in the plane z = 0 with outline `corners`, facing +z)
/// beside its pdf per solid angle, binned about the light's centre.
fn light_warp(
    name: String,
    emitters: &[Emitter],
    corners: &[Vec3],
    points: LightPoints,
    (p, normal): (Vec3, Vec3),
) -> Warp {
    let lights = std::rc::Rc::new(
        Lights::build(emitters.to_vec(), emitters.len(), Vec3::ZERO, 10.0)
            .expect("a light of one or two triangles"),
    );
    let (l1, l2) = (lights.clone(), lights);
    let centre = corners.iter().sum::<Vec3>() / corners.len() as f32;
    let pole = (centre - p).normalize();
    let z_lo = corners
        .iter()
        .map(|c| (*c - p).normalize().dot(pole))
        .fold(1.0f32, f32::min)
        - 0.02;
    let corners = corners.to_vec();
    (
        name,
        Box::new(move |u| {
            l1.sampler(points, LightChoice::Power)
                .sample(p, normal, 0.5, u)
                .map(|s| s.wi)
        }),
        Box::new(move |w: Vec3| {
            // the point of the light plane in direction w, if it lies on the light
            if w.z >= 0.0 {
                return 0.0;
            }
            let y = p + w * (-p.z / w.z);
            let k = corners.len();
            let inside = (0..k).all(|i| {
                let (a, b) = (corners[i], corners[(i + 1) % k]);
                (b - a).cross(y - a).z >= 0.0
            });
            if inside {
                l2.sampler(points, LightChoice::Power).pdf(0, p, normal, y)
            } else {
                0.0
            }
        }),
        // fine quadrature, and a floor of half a sample per bin: the pdf steps to 0 at the
        // light's outline, and a sliver of a bin it crosses must not expect nothing
        Chi2Binning {
            pole,
            z_lo,
            quadrature: 24,
            floor: 0.5,
            ..Default::default()
        },
    )
}

/// The directional distribution a path guide learns at one point from a known incident
/// radiance `L(ω)` (0.1 everywhere, a lobe `40 max(0, ω·s)⁴⁰` and a window of 3 where
/// `ω_x > 0.8`): four training iterations of 60,000 uniform directions each, recorded as the
/// renderer records them (`L/p`), the tree refined between iterations.
pub fn trained_guide_leaf() -> crate::guiding::DTree {
    use crate::guiding::{dir_to_canonical, Record, SdTree};
    let at = Vec3::splat(0.5);
    let mut tree = SdTree::new(Vec3::ZERO, Vec3::ONE);
    let s = Vec3::new(0.3, -0.4, 0.6).normalize();
    let radiance = |d: Vec3| {
        let window = if d.x > 0.8 { 3.0 } else { 0.0 };
        0.1 + 40.0 * d.dot(s).max(0.0).powi(40) + window
    };
    let p = 0.25 / std::f32::consts::PI;
    let mut u = IndependentSampler::new(0x9e1d);
    for it in 0..4u32 {
        let leaf = tree.leaf_at(at);
        let n = 60_000u32;
        let records = (0..n)
            .map(|i| {
                u.start_pixel_sample(UVec2::new(it, 0), i);
                let c = u.next_2d();
                let d = crate::guiding::canonical_to_dir(c);
                let l = radiance(d);
                Record {
                    leaf,
                    point: dir_to_canonical(d),
                    value: l / p,
                    product: l,
                    pdf: p,
                    p_bsdf: p,
                    p_guide: p,
                }
            })
            .collect::<Vec<_>>();
        tree.add_records(&records);
        tree.finish_iteration(n as u64);
    }
    tree.sampling(tree.leaf_at(at)).clone()
}

/// Test every warp; write the picture and the JSON asked for.
pub fn run(req: &WarptestRequest) -> Result<WarptestOutcome> {
    super::check_picture_and_json(&req.output, &req.json, false)?;
    let rows: Vec<WarpRow> = warps()
        .into_iter()
        .enumerate()
        .map(|(k, (name, sample, pdf, b))| {
            let mut s = IndependentSampler::new(req.seed.wrapping_add(k as u64));
            let mut i = 0u32;
            let points = move || {
                s.start_pixel_sample(UVec2::ZERO, i);
                i += 1;
                s.next_2d()
            };
            let scale = req.pdf_scale;
            let (r, obs, exp) =
                chi2_directions_binned(sample, |w| scale * pdf(w), points, req.n as usize, &b);
            WarpRow {
                warp: name,
                chi2: r.statistic,
                dof: r.dof,
                p_value: r.p_value,
                pdf_integral: r.pdf_integral,
                bins: (obs, exp, (b.phi_bins as u32, b.z_bins as u32)),
            }
        })
        .collect();
    let mut written = Vec::new();
    if let Some(p) = &req.output {
        // every row at one binning (nearest bin), so the rows align
        let (w, h) = (80, 40);
        let rows_px = resampled(&rows, (w, h));
        let view: Vec<(String, &[f64], &[f64])> = rows_px
            .iter()
            .map(|(l, a, b)| (l.clone(), &a[..], &b[..]))
            .collect();
        crate::analysis::maps::write_density_rows(p, &view, (w, h))?;
        written.push(p.clone());
    }
    if let Some(p) = &req.json {
        super::write_json(p, &rows)?;
        written.push(p.clone());
    }
    Ok(WarptestOutcome { rows, written })
}

/// Each row's bins resampled (nearest bin) to `w × h`, so the picture's rows align.
fn resampled(rows: &[WarpRow], (w, h): (u32, u32)) -> Vec<(String, Vec<f64>, Vec<f64>)> {
    rows.iter()
        .map(|r| {
            let (rw, rh) = r.bins.2;
            let pick = |v: &[f64]| -> Vec<f64> {
                (0..w * h)
                    .map(|k| {
                        let (x, y) = (k % w, k / w);
                        v[((y * rh / h) * rw + x * rw / w) as usize]
                    })
                    .collect()
            };
            (
                format!(
                    "{}: p = {:.3}, ∫pdf = {:.4}",
                    r.warp, r.p_value, r.pdf_integral
                ),
                pick(&r.bins.0),
                pick(&r.bins.1),
            )
        })
        .collect()
}

/// Every warp's row, and the files written.
#[derive(Clone, Debug)]
pub struct WarptestOutcome {
    pub rows: Vec<WarpRow>,
    pub written: Vec<PathBuf>,
}

impl WarptestOutcome {
    /// The rows as a table for the terminal.
    pub fn table(&self) -> String {
        table(&self.rows)
    }
}

/// `rows` as a table for the terminal.
pub fn table(rows: &[WarpRow]) -> String {
    let mut s = format!(
        "{:<44} {:>12} {:>6} {:>10} {:>10}\n",
        "warp", "chi2", "dof", "p", "∫pdf"
    );
    for r in rows {
        s += &format!(
            "{:<44} {:>12.1} {:>6} {:>10.4} {:>10.5}\n",
            r.warp, r.chi2, r.dof, r.p_value, r.pdf_integral
        );
    }
    s
}
