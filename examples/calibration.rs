//! The calibration table of the README: on every shipped scene, for each sampler and several
//! seeds, the image's own error estimate (from 4 replicates, and per sample) against the error
//! measured against an independent-sample reference; and a log-log calibration plot. Then what
//! the 4 replicates cost: the measured MSE of the same renders as one set of all their samples
//! (pooled over seeds: Σ MSE(4 sets of N/4) / Σ MSE(1 set of N)).
//!
//! `cargo run --release --example calibration -- [--size W H] [--spp N] [--ref-spp M]
//! [--seeds K] [--plot FILE.png]`

use std::path::Path;
use vrpt::analysis::calibration::{calibrate, one_set, reference_settings, Case};
use vrpt::output::render_image;
use vrpt::render::{render_passes, NoProgress, PassPlan, RenderSettings};
use vrpt::sampler::SamplerKind;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let flag = |name: &str, k: usize| -> Option<String> {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + k).cloned())
    };
    let num = |name: &str, k: usize, d: u32| flag(name, k).map_or(d, |v| v.parse().unwrap());
    let (w, h) = (num("--size", 1, 64), num("--size", 2, 48));
    let spp = num("--spp", 1, 64);
    let ref_spp = num("--ref-spp", 1, 16384);
    let seeds: Vec<u64> = (1..=num("--seeds", 1, 4) as u64).collect();
    let samplers = [
        SamplerKind::Independent,
        SamplerKind::Stratified,
        SamplerKind::Sobol,
    ];
    let scenes = [
        "cornell-box",
        "glossy-plates",
        "lit-checker",
        "checker-plane",
        "night-hall",
        "door",
    ];
    println!(
        "{w}x{h}, {spp} spp in 4 replicates, reference {ref_spp} spp independent; \
         MSE estimated / measured (median over {} seeds, and the range)",
        seeds.len()
    );
    println!(
        "{:<14} {:<12} {:>11} {:>11} {:>9} {:>17} {:>11}",
        "scene", "sampler", "measured", "estimated", "ratio", "range", "per-sample"
    );
    let mut all: Vec<(String, Case)> = Vec::new();
    let mut cost = String::new();
    for name in scenes {
        let scene = vrpt::scene::load(Path::new(&format!("scenes/{name}")))?;
        let base = RenderSettings {
            width: w,
            height: h,
            spp,
            replicates: 4,
            ..RenderSettings::for_scene(&scene)
        };
        let rs = reference_settings(&base, ref_spp, 1 << 40);
        let r = render_passes(&scene, &rs, &PassPlan::default(), &NoProgress)?;
        let meta = vrpt::output::RenderMetadata::new(&scene, &rs, &r.stats);
        let reference = render_image(&r.film, &meta);
        let cases = calibrate(&scene, &base, &reference, &samplers, &seeds)?;
        let single = one_set(&scene, &base, &reference, &samplers, &seeds)?;
        for (k, sampler) in samplers.iter().enumerate() {
            let at = k * seeds.len()..(k + 1) * seeds.len();
            let four: f64 = cases[at.clone()].iter().map(|c| c.measured_mse).sum();
            let one: f64 = single[at].iter().sum();
            cost += &format!(
                "{:<14} {:<12} {:>11.3e} {:>11.3e} {:>9.2}\n",
                name,
                sampler.to_string(),
                four / seeds.len() as f64,
                one / seeds.len() as f64,
                four / one
            );
        }
        for sampler in samplers {
            let c: Vec<&Case> = cases.iter().filter(|c| c.sampler == sampler).collect();
            let med = |f: &dyn Fn(&Case) -> f64| {
                let mut v: Vec<f64> = c.iter().map(|c| f(c)).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let ratios: Vec<f64> = c.iter().map(|c| c.mse_ratio()).collect();
            let lo = ratios.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = ratios.iter().copied().fold(0.0, f64::max);
            println!(
                "{:<14} {:<12} {:>11.3e} {:>11.3e} {:>9.2} {:>8.2}..{:<8.2} {:>11.2}",
                name,
                sampler.to_string(),
                med(&|c| c.measured_mse),
                med(&|c| c.estimated_mse),
                med(&|c| c.mse_ratio()),
                lo,
                hi,
                med(&|c| c.per_sample_ratio())
            );
        }
        all.extend(cases.into_iter().map(|c| (name.to_string(), c)));
    }
    let within = all
        .iter()
        .filter(|(_, c)| (0.5..=2.0).contains(&c.mse_ratio()))
        .count();
    println!(
        "replicate estimate within 2x of the measured MSE: {within} of {} cases",
        all.len()
    );
    println!(
        "\nwhat 4 replicates cost: measured MSE of 4 sets of {} against one set of {spp} \
         (means over seeds)\n{:<14} {:<12} {:>11} {:>11} {:>9}\n{cost}",
        spp / 4,
        "scene",
        "sampler",
        "4 sets",
        "1 set",
        "ratio"
    );
    if let Some(p) = flag("--plot", 1) {
        let points: Vec<(f64, f64, String)> = all
            .iter()
            .map(|(s, c)| {
                (
                    c.measured_mse,
                    c.estimated_mse,
                    format!("{s} {}", c.sampler),
                )
            })
            .collect();
        let per_sample: Vec<(f64, f64)> = all
            .iter()
            .map(|(_, c)| (c.measured_mse, c.per_sample_mse))
            .collect();
        vrpt::analysis::plots::write_calibration_plot(Path::new(&p), &points, &per_sample)?;
        println!("wrote {p}");
    }
    Ok(())
}
