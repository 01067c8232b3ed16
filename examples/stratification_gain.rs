//! How much stratification gains, per candidate strategy and per pass size: the measurement
//! behind `docs/performance.md`'s "What the pilots misjudge, measured".
//!
//! For each candidate (`mis`, `mis+reuse4`, … as `--auto-candidates` names them) and each pass
//! size P, the scene is rendered as 4 replicates of P samples per pixel (each replicate one
//! stratified set of P), and two per-sample errors are read from the same render, both against
//! one reference's `r² + 0.01` (a long independent-points render) so every candidate weighs the
//! pixels alike:
//!
//! - `S`: the pixels' sample variance over all 4P samples, times 4P: what one sample would give
//!   if the samples were independent (a stratified sample is still uniform on its own, so its
//!   variance is the independent one's);
//! - `W`: the variance of the mean estimated from the 4 replicates' spread, times 4P: what one
//!   sample is worth inside a stratified set of P.
//!
//! `g = S/W` is the stratification gain at P (1 at P = 1, where a set is one sample). Both are
//! given for the relMSE (what `--strategy auto` compares) and for the MSE (what
//! `tools/peers/mitsuba_race.py` compares), with the render's seconds, so the efficiency
//! `1/(W × seconds)` of the candidates can be set side by side at each P. Medians over the seeds.
//!
//! `cargo run --release --example stratification_gain -- SCENE [--size W H]
//! [--candidates mis,mis+reuse4] [--passes 4,16,64] [--seeds 3] [--ref-spp 4096]`

use glam::Vec3;
use std::path::Path;
use vrpt::analysis::calibration::reference_settings;
use vrpt::estimate::{rel_mse_against, squared_reference};
use vrpt::render::auto::Candidates;
use vrpt::render::{render_passes, NoProgress, PassPlan, RenderSettings};

/// Replicates of every measured render.
const REPLICATES: u32 = 4;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let flag = |name: &str, k: usize| -> Option<String> {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + k).cloned())
    };
    let scene_path = args
        .get(1)
        .filter(|a| !a.starts_with("--"))
        .ok_or("usage: stratification_gain SCENE [--size W H] [--candidates LIST] [--passes LIST] [--seeds N] [--ref-spp N]")?;
    let scene = vrpt::scene::load(Path::new(scene_path))?;
    let mut base = RenderSettings::for_scene(&scene);
    if let (Some(w), Some(h)) = (flag("--size", 1), flag("--size", 2)) {
        (base.width, base.height) = (w.parse()?, h.parse()?);
    }
    let candidates =
        Candidates::parse(&flag("--candidates", 1).unwrap_or("mis,mis+reuse4".into()))?;
    let passes: Vec<u32> = flag("--passes", 1)
        .unwrap_or("4,16,64".into())
        .split(',')
        .map(|p| p.trim().parse())
        .collect::<Result<_, _>>()?;
    let seeds: u64 = flag("--seeds", 1).map_or(Ok(3), |s| s.parse())?;
    let ref_spp: u32 = flag("--ref-spp", 1).map_or(Ok(4096), |s| s.parse())?;

    let reference = reference_settings(&base, ref_spp, 4242);
    let r = render_passes(&scene, &reference, &PassPlan::default(), &NoProgress)?;
    let r2 = squared_reference(base.width, &r.film.mean_image(), &r.film.variance_image());
    println!(
        "{scene_path} at {}x{}, {REPLICATES} replicates of P spp, medians of {seeds} seeds; \
         per-sample errors against a {ref_spp}-spp reference",
        base.width, base.height
    );
    println!(
        "{:<22} {:>5} {:>11} {:>11} {:>6} {:>11} {:>6} {:>9}",
        "candidate", "P", "S relMSE", "W relMSE", "g", "W MSE", "g MSE", "seconds"
    );
    for c in &candidates.0 {
        for &p in &passes {
            let mut rows = Vec::new();
            for seed in 1..=seeds {
                let s = RenderSettings {
                    spp: REPLICATES * p,
                    replicates: REPLICATES,
                    seed,
                    ..c.settings(&base)
                };
                let r = render_passes(&scene, &s, &PassPlan::default(), &NoProgress)?;
                let n = s.spp as f64;
                let (pooled, spread) = (r.film.variance_image(), &r.estimate.variance);
                let mse = |v: &[Vec3]| {
                    v.iter().map(|x| x.element_sum() as f64).sum::<f64>() / (3 * v.len()) as f64
                };
                rows.push([
                    rel_mse_against(&r2, &pooled).0 * n,
                    rel_mse_against(&r2, spread).0 * n,
                    mse(&pooled) * n,
                    mse(spread) * n,
                    r.stats.elapsed.as_secs_f64(),
                ]);
            }
            let median = |k: usize| {
                let mut v: Vec<f64> = rows.iter().map(|r| r[k]).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let (s, w, sm, wm, t) = (median(0), median(1), median(2), median(3), median(4));
            println!(
                "{:<22} {:>5} {:>11.4e} {:>11.4e} {:>6.2} {:>11.4e} {:>6.2} {:>9.2}",
                c.to_string(),
                p,
                s,
                w,
                s / w,
                wm,
                sm / wm,
                t
            );
        }
    }
    Ok(())
}
