//! Which relMSE denominator lets `--strategy auto`'s pilots, at their few samples, rank `mis`
//! against `mis+reuse4` as a converged reference does: the measurement behind the pilots'
//! inverse-variance pooled mean (`src/render/auto/pilot.rs`, `shared_denominator`).
//!
//! Both candidates render the whole image as 4 replicates of `M` spp (new seeds per line); each
//! line prints the ratio of their relMSEs (mis over reuse, per sample alike) against `r² + 0.01`
//! with `r²` from: `truth` (a 2048-spp independent-points render), `ivw` / `givw` (the
//! [`squared_reference`] of the candidates' images pooled by inverse variance per pixel / per
//! image, the latter what auto uses), `pilots` (equal weights, what auto used before), `F2`
//! (the pooled mean squared), `F2-v` (that minus its variance, at least 0), their 3×3 and 5×5
//! box averages, and the 3×3 box average of the mean, squared.
//!
//! `cargo run --release --example pilot_denominators -- SCENE M SEEDS`
use glam::{DVec3, Vec3};
use std::path::Path;
use vrpt::analysis::calibration::reference_settings;
use vrpt::estimate::{rel_mse_against, squared_reference};
use vrpt::render::auto::Candidates;
use vrpt::render::{render_passes, NoProgress, PassPlan, RenderSettings};

fn boxk(w: usize, h: usize, m: &[DVec3], k: i64) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; w * h];
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let (mut s, mut n) = (DVec3::ZERO, 0.0);
            for dy in -k..=k {
                for dx in -k..=k {
                    let (xx, yy) = (x + dx, y + dy);
                    if xx >= 0 && yy >= 0 && xx < w as i64 && yy < h as i64 {
                        s += m[(yy * w as i64 + xx) as usize];
                        n += 1.0;
                    }
                }
            }
            out[(y * w as i64 + x) as usize] = s / n;
        }
    }
    out
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = vrpt::scene::load(Path::new(&a[1])).unwrap();
    let m: u32 = a[2].parse().unwrap();
    let seeds: u64 = a[3].parse().unwrap();
    let base = RenderSettings::for_scene(&scene);
    let (w, h) = (base.width as usize, base.height as usize);
    let rs = reference_settings(&base, 2048, 4242);
    let r = render_passes(&scene, &rs, &PassPlan::default(), &NoProgress).unwrap();
    let truth: Vec<DVec3> = r
        .film
        .mean_image()
        .iter()
        .map(|v| (*v * *v).as_dvec3())
        .collect();
    let cands = Candidates::parse("mis,mis+reuse4").unwrap().0;
    println!(
        "{} {}x{} m {m}: per-sample relMSE ratio mis/reuse4 by denominator",
        a[1], w, h
    );
    for seed in 1..=seeds {
        let mut runs = Vec::new();
        for c in &cands {
            let s = RenderSettings {
                spp: 4 * m,
                replicates: 4,
                seed: 1000 + seed,
                ..c.settings(&base)
            };
            let r = render_passes(&scene, &s, &PassPlan::default(), &NoProgress).unwrap();
            runs.push((r.film.mean_image(), r.estimate.variance.clone()));
        }
        let k = runs.len() as f32;
        let n = runs[0].0.len();
        let mut mean = vec![Vec3::ZERO; n];
        let mut var = vec![Vec3::ZERO; n];
        for (mu, v) in &runs {
            for i in 0..n {
                mean[i] += mu[i] / k;
                var[i] += v[i] / (k * k);
            }
        }
        let f2: Vec<DVec3> = mean.iter().map(|v| (*v * *v).as_dvec3()).collect();
        let unb: Vec<DVec3> = f2
            .iter()
            .zip(&var)
            .map(|(f, v)| (*f - v.as_dvec3()).max(DVec3::ZERO))
            .collect();
        // inverse-variance weighted mean of the candidates, per pixel and channel
        let (mut iw_m, mut iw_v) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        for i in 0..n {
            let (mut sw, mut sm) = (Vec3::ZERO, Vec3::ZERO);
            for (mu, v) in &runs {
                let wgt = Vec3::ONE / v[i].max(Vec3::splat(1e-12));
                sw += wgt;
                sm += mu[i] * wgt;
            }
            iw_m[i] = sm / sw;
            iw_v[i] = Vec3::ONE / sw;
        }
        // global weights: 1/(mean variance) per candidate
        let gw: Vec<f32> = runs
            .iter()
            .map(|(_, v)| {
                1.0 / (v.iter().map(|x| x.element_sum()).sum::<f32>() / n as f32).max(1e-12)
            })
            .collect();
        let gsum: f32 = gw.iter().sum();
        let (mut g_m, mut g_v) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        for i in 0..n {
            for ((mu, v), wgt) in runs.iter().zip(&gw) {
                g_m[i] += mu[i] * (wgt / gsum);
                g_v[i] += v[i] * (wgt / gsum).powi(2);
            }
        }
        let dens: Vec<(&str, Vec<DVec3>)> = vec![
            ("ivw", squared_reference(w as u32, &iw_m, &iw_v)),
            ("givw", squared_reference(w as u32, &g_m, &g_v)),
            ("truth", truth.clone()),
            ("pilots", squared_reference(w as u32, &mean, &var)),
            ("F2", f2.clone()),
            ("F2-v", unb.clone()),
            ("box3(F2-v)", boxk(w, h, &unb, 1)),
            ("box5(F2-v)", boxk(w, h, &unb, 2)),
            (
                "box3(F)^2",
                boxk(
                    w,
                    h,
                    &mean.iter().map(|v| v.as_dvec3()).collect::<Vec<_>>(),
                    1,
                )
                .iter()
                .map(|b| *b * *b)
                .collect(),
            ),
        ];
        let mut line = format!("seed {seed}:");
        for (name, d) in &dens {
            let e = |v: &[Vec3]| rel_mse_against(d, v).0;
            line += &format!(" {name} {:.3}", e(&runs[0].1) / e(&runs[1].1));
        }
        println!("{line}");
    }
}
