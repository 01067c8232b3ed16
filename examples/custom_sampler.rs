//! A sampler of your own, through vrpt's renderer and harness, from outside the crate.
//!
//! `Weyl` is a Kronecker (Weyl) sequence with a Cranley–Patterson rotation per pixel: dimension
//! `d` of sample `i` in pixel `p` is `frac(s(p, d) + i·α_d)`, with `α_d = frac(√q_d)` for the
//! d-th prime `q_d` (irrational, so the points fill [0, 1) evenly) and `s(p, d)` a uniform shift
//! hashed from (seed, pixel, dimension). Each sample is uniform on its own (the shift is), so
//! every estimate is unbiased; consecutive indices are evenly spread per dimension, and pairs of
//! dimensions form a rank-1 lattice rule. A 2D draw takes two dimensions.
//!
//! The example renders a reference (Sobol, many spp), then compares Weyl against the built-in
//! samplers at equal spp on the Cornell box (MIS) and on lit-checker (NEE, points by area on its
//! large light), prints the tables and writes an HTML report per scene:
//!
//! ```sh
//! cargo run --release --example custom_sampler            # 64×64 and 64×48, ~1 minute on 2 cores
//! VRPT_EXAMPLE_QUICK=1 cargo run --release --example custom_sampler   # tiny, for CI
//! ```

use glam::{UVec2, Vec2};
use std::path::Path;
use vrpt::analysis::experiments::{compare_entries, Entry, ExperimentSettings};
use vrpt::analysis::report::Report;
use vrpt::math::{hash_words, u64_to_unit_f32};
use vrpt::render::{render, NoProgress, RenderSettings, SamplePass};
use vrpt::sampler::{Sampler, SamplerKind};
use vrpt::strategy::Strategy;

/// The sampler: a Weyl sequence per dimension, rotated per pixel.
#[derive(Clone)]
struct Weyl {
    seed: u64,
    /// `α_d` for the first dimensions (then independent numbers: paths rarely go that deep).
    alpha: Vec<f64>,
    pixel: UVec2,
    index: u32,
    dim: usize,
}

impl Weyl {
    fn new(seed: u64) -> Weyl {
        let primes = (2u64..).filter(|&n| (2..n).take_while(|k| k * k <= n).all(|k| n % k != 0));
        let alpha = primes.take(64).map(|q| (q as f64).sqrt().fract()).collect();
        Weyl {
            seed,
            alpha,
            pixel: UVec2::ZERO,
            index: 0,
            dim: 0,
        }
    }
}

impl Sampler for Weyl {
    fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
        (self.pixel, self.index, self.dim) = (pixel, index, 0);
    }

    fn next_1d(&mut self) -> f32 {
        let (p, d) = (self.pixel, self.dim as u64);
        self.dim += 1;
        let shift = u64_to_unit_f32(hash_words(&[self.seed, p.x as u64, p.y as u64, d]));
        let x = match self.alpha.get(d as usize) {
            Some(a) => (shift as f64 + self.index as f64 * a).fract(),
            None => u64_to_unit_f32(hash_words(&[
                self.seed,
                p.x as u64,
                p.y as u64,
                d,
                self.index as u64,
            ])) as f64,
        };
        (x as f32).min(vrpt::sampler::ONE_MINUS_EPSILON)
    }

    fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_1d(), self.next_1d())
    }
}

fn main() -> vrpt::Result<()> {
    let quick = std::env::var_os("VRPT_EXAMPLE_QUICK").is_some();
    let (spp, reference_spp, runs) = if quick { (16, 1024, 2) } else { (64, 16384, 4) };
    for (name, (w, h), rest) in [
        ("cornell-box", (64, 64), "phong+mis"),
        ("lit-checker", (64, 48), "cosine+nee+area+power"),
    ] {
        let (w, h) = if quick { (16, 12) } else { (w, h) };
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(name);
        let scene = vrpt::scene::load(&dir)?;
        let strategy_of =
            |s: &str| Strategy::parse(&format!("{s}+{rest}")).map_err(vrpt::Error::Settings);
        // the reference: Sobol points, seed 1000 (no run below uses it)
        let settings = RenderSettings {
            width: w,
            height: h,
            spp: reference_spp,
            seed: 1000,
            strategy: strategy_of("sobol")?,
            ..RenderSettings::default()
        };
        let (film, _) = render(&scene, &settings, &NoProgress)?;
        let reference = vrpt::image_io::RgbImage {
            width: w,
            height: h,
            pixels: film.mean_image(),
            variance: Some(film.variance_image()),
            ..Default::default()
        };
        let s = ExperimentSettings {
            width: w,
            height: h,
            max_depth: settings.max_depth,
            seed: 1,
            reference_seeds: vec![1000],
            runs,
            threads: None,
            regions: Vec::new(),
        };
        // the built-in samplers (independent first: the baseline), then Weyl with the same
        // directions and lights
        let mut entries = Vec::new();
        for kind in [
            SamplerKind::Independent,
            SamplerKind::Stratified,
            SamplerKind::Sobol,
        ] {
            entries.push(Entry::builtin(Strategy {
                sampler: kind,
                ..strategy_of("independent")?
            }));
        }
        entries.push(Entry::custom(
            "weyl",
            |seed, _: SamplePass| Weyl::new(seed),
            strategy_of("independent")?,
        ));
        let c = compare_entries(&scene, &reference, &entries, spp, None, &s, &NoProgress)?;
        println!("{name}, {w}×{h}, {spp} spp, {runs} runs, against a {reference_spp}-spp Sobol reference:");
        print!("{}", c.table());
        let out = std::env::temp_dir().join(format!("vrpt-custom-sampler-{name}.html"));
        let title = format!("{name}: a custom sampler against the built-in ones");
        Report::for_comparison(&c, &reference, &[], (&title, false), Vec::new())?.write(&out)?;
        println!("report: {}\n", out.display());
    }
    Ok(())
}
