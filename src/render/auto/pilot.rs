//! The pilots of `--strategy auto` (the module doc above says what they measure): each
//! candidate rendered on the pilots' strip of tiles with the pilots' seed and replicates, a
//! guided candidate's guide learned first, and the rows measured against one denominator.

use super::*;
use crate::estimate::{rel_mse_against, squared_reference};
use crate::render::{learn_guide_with, render_passes, NoProgress, Rendered, TILE};

/// The pilots of one render: what every candidate's pilot shares, and the guides the guided
/// candidates learned.
pub(super) struct Pilots<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    plan: &'a PassPlan,
    candidates: &'a [Candidate],
    cost: Cost,
    strip: Option<Arc<TileStrip>>,
    /// The pilots' image: the strip's width (or the image's).
    pub(super) width: u32,
    height: u32,
    /// The pilots' share of the image's pixels.
    pub(super) share: f64,
    /// The tiles the pilots render, and the image's (partial ones included).
    pub(super) tiles: (u32, u32),
    /// Each guided candidate's guide, learned on the strip before its first pilot (see
    /// [`GUIDE_SHARE`]), kept for the render if it is chosen.
    pub(super) guides: Vec<Option<Arc<LearnedGuide>>>,
    /// The image's edge map, found once with the render's seed and the first candidate's
    /// integrator, every pilot's (independent of every pilot's and the render's samples, so
    /// the choice and the image stay unbiased), and the render's where it fits it.
    pub(super) edges: Option<Arc<EdgeMap>>,
}

impl<'a> Pilots<'a> {
    /// The pilots of a render of `settings` under `plan` among `candidates`, costs counted as
    /// `cost`, on the strip [`pilot_strip`] gives.
    pub(super) fn new(
        scene: &'a Scene,
        settings: &'a RenderSettings,
        plan: &'a PassPlan,
        candidates: &'a [Candidate],
        cost: Cost,
    ) -> Result<Self> {
        let first = candidates.first().map(|c| c.settings(settings));
        let edges = match &first {
            Some(s) => {
                let camera = crate::render::strip_camera(scene, s, plan)?;
                crate::render::edges::edge_map(scene, &camera, s, plan).map(Arc::new)
            }
            None => None,
        };
        let strip = pilot_strip(settings.width, settings.height).map(Arc::new);
        let (width, height) = strip
            .as_ref()
            .map_or((settings.width, settings.height), |s| s.size());
        let image_tiles = settings.width.div_ceil(TILE) * settings.height.div_ceil(TILE);
        let tiles = strip
            .as_ref()
            .map_or(image_tiles, |s| s.origins.len() as u32);
        let share =
            (width as f64 * height as f64) / (settings.width as f64 * settings.height as f64);
        Ok(Pilots {
            scene,
            settings,
            plan,
            candidates,
            cost,
            strip,
            width,
            height,
            share,
            tiles: (tiles, image_tiles),
            guides: vec![None; candidates.len()],
            edges,
        })
    }

    /// Whether guided candidate `twin`, rendered after pilots that took `elapsed`, would
    /// read its gate before its training ends ([`crate::render::gate::reads_within`], at
    /// `per_spp` seconds a training spp of the image under a time limit); a render that does
    /// not gate (`--guide-gate off`) reads nothing and is asked for as it is.
    pub(super) fn twin_reads(
        &self,
        twin: Candidate,
        per_spp: Option<f64>,
        elapsed: Duration,
    ) -> bool {
        let settings = twin.settings(self.settings);
        let plan = PassPlan {
            time_limit: (self.plan.time_limit).map(|t| t.saturating_sub(elapsed)),
            ..self.plan.clone()
        };
        let pixels = settings.width as u64 * settings.height as u64;
        let budget = TrainingBudget::of_render(&settings, &plan);
        !crate::render::gates(&settings, &plan)
            || crate::render::gate::reads_within(budget, pixels, per_spp)
    }

    /// The pilot of candidate `k` at `spp` samples per pixel (all replicates).
    pub(super) fn run(&mut self, k: usize, spp: u32) -> Result<Pilot> {
        self.run_as(k, spp, PILOT_REPLICATES)
    }

    /// Candidate `k` on the pilots' strip with the pilots' seed at `spp` samples per pixel as
    /// `replicates` replicates (the probe: [`PROBE_SPP`] as one).
    pub(super) fn run_as(&mut self, k: usize, spp: u32, replicates: u32) -> Result<Pilot> {
        let s = RenderSettings {
            seed: pilot_seed(self.settings.seed),
            first_sample: 0,
            spp,
            replicates,
            width: self.width,
            height: self.height,
            ..self.candidates[k].settings(self.settings)
        };
        let mut p = PassPlan {
            stop: self.plan.stop.clone(),
            strip: self.strip.clone(),
            edges: self.edges.clone(),
            ..PassPlan::default()
        };
        if s.strategy.directions == Directions::Guided {
            p.guide = Some(self.guide(k, &s, &p)?);
        }
        let r = render_passes(self.scene, &s, &p, &NoProgress)?;
        Ok(pilot_of(self.candidates[k], r, self.cost))
    }

    /// Guided candidate `k`'s guide, learned once on the strip with the render's seed (the
    /// training's own seeds are mixed from it) within [`guide_budget`]; `s` and `p` are its
    /// pilot's settings and plan.
    fn guide(&mut self, k: usize, s: &RenderSettings, p: &PassPlan) -> Result<Arc<LearnedGuide>> {
        if let Some(g) = &self.guides[k] {
            return Ok(g.clone());
        }
        let learner = RenderSettings {
            seed: self.settings.seed,
            ..s.clone()
        };
        let budget = guide_budget(self.settings.spp, self.share, self.plan.time_limit);
        let (tree, stats) = learn_guide_with(self.scene, &learner, p, budget)?;
        let stats = stats.guide.unwrap_or_default();
        let g = Arc::new(LearnedGuide { tree, stats });
        self.guides[k] = Some(g.clone());
        Ok(g)
    }
}

/// A candidate's pilot: its samples per pixel, cost and wall seconds, and its image's mean and
/// estimated variance per pixel.
pub(super) struct Pilot {
    pub(super) candidate: Candidate,
    pub(super) spp: u32,
    pub(super) cost: f64,
    pub(super) seconds: f64,
    pub(super) mean: Vec<glam::Vec3>,
    pub(super) variance: Vec<glam::Vec3>,
    /// The share of its paths' light that was caustic ([`crate::integrator::RayCounts::caustic_share`]).
    pub(super) caustic: f64,
    /// The share of its paths' light found from the second vertex on
    /// ([`crate::integrator::RayCounts::indirect_share`]).
    pub(super) indirect: f64,
}

/// The pilots' rows, every relMSE measured against one denominator ([`rel_mse_against`]): the
/// squared reference ([`squared_reference`]) of one mean of all the pilots' images (each an
/// unbiased image of the same tiles), so every candidate weighs the pixels alike, and a pixel
/// where one pilot met a rare bright path does not lower that pilot's relMSE by its own bright
/// mean. The mean weighs each pilot's image by the inverse of its mean estimated variance over
/// the pixels, `wᵢ ∝ 1/mean(vᵢ)` (the least-variance combination of unbiased images, with one
/// weight per image: weights per pixel follow each pixel's noisy variance estimate, and on the
/// gap and glass they read worse than equal weights), its variance `Σ wᵢ² vᵢ`, as if the pilots'
/// errors were independent (they share their random numbers, so it is somewhat larger). With
/// equal weights, the mean of a noisy candidate and a precise one was as noisy as half the noisy
/// one, and at a pilot's 2 samples per replicate its `r²` (mostly a box average of that noise)
/// was far above the truth in the dark pixels, where path reuse gains most: against a 2048-spp
/// reference the per-sample relMSE of mis over `mis+reuse4` at 2 spp per replicate is 8.1–8.9 on
/// the door, 4.8–6.1 on the gap; the equal-weight denominator read 2.8 and 1.8–1.9, this one
/// 7.0–7.3 and 4.2–5.0 (textured at 20 spp per replicate 1.53–1.56 either way; glass 1.85 and
/// 1.95 against 1.42–1.47: it reads path reuse too well there either way). The weights are at
/// least `1e-30` apart from zero, so a pilot with no variance at all does not divide by zero.
pub(super) fn shared_denominator(width: u32, pilots: &[Pilot]) -> Vec<PilotRow> {
    let n = pilots.first().map_or(0, |p| p.mean.len());
    let weights: Vec<f64> = (pilots.iter())
        .map(|p| {
            let mean_variance = (p.variance.iter())
                .map(|v| v.as_dvec3().element_sum())
                .sum::<f64>()
                / (3 * n.max(1)) as f64;
            1.0 / mean_variance.max(1e-30)
        })
        .collect();
    let total: f64 = weights.iter().sum();
    let (mut mean, mut var) = (vec![glam::Vec3::ZERO; n], vec![glam::Vec3::ZERO; n]);
    for (p, w) in pilots.iter().zip(&weights) {
        let w = (w / total) as f32;
        for i in 0..n {
            mean[i] += p.mean[i] * w;
            var[i] += p.variance[i] * (w * w);
        }
    }
    let r2 = squared_reference(width, &mean, &var);
    pilots
        .iter()
        .map(|p| {
            let (rel_mse, rel_mse_se) = rel_mse_against(&r2, &p.variance);
            PilotRow {
                candidate: p.candidate,
                spp: p.spp,
                rel_mse,
                rel_mse_se,
                cost: p.cost,
                efficiency: 1.0 / (rel_mse * p.cost),
                seconds: p.seconds,
            }
        })
        .collect()
}

/// What the pilot `r` of `candidate` measured: its image's mean and estimated variance per
/// pixel, and its cost counted as `cost` says.
fn pilot_of(candidate: Candidate, r: Rendered, cost: Cost) -> Pilot {
    let rays = &r.stats.rays;
    let seconds = r.stats.elapsed.as_secs_f64();
    let spent = match cost {
        Cost::Rays => {
            let connections = rays.connection as f64;
            let weighed = (rays.total() as f64 - connections) + CONNECTION_COST * connections;
            let ears = match candidate.roulette {
                Roulette::Ears => EARS_RAY_COST,
                Roulette::Classic => 1.0,
            };
            let guided = match candidate.strategy.directions {
                Directions::Guided => GUIDED_RAY_COST,
                _ => 1.0,
            };
            ears * guided * weighed
        }
        Cost::Seconds => seconds,
    };
    Pilot {
        candidate,
        spp: r.spp,
        cost: spent,
        seconds,
        mean: r.film.mean_image(),
        variance: r.estimate.variance,
        caustic: rays.caustic_share(),
        indirect: rays.indirect_share(),
    }
}
