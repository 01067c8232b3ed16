//! Adaptive rounds: each round's samples go where the estimated relative error is, and the
//! image weighs each round by its planned size (see [`crate::estimate`]); under a time limit
//! the rounds' sizes follow the clock.

use super::*;

/// An adaptive render between rounds.
struct Rounds {
    /// Every sample so far, unweighted.
    raw: Film,
    /// Each replicate's means, weighted by the rounds' planned sizes.
    replicates: Replicates,
    /// Each pixel's next sample index of every replicate (the same in all of them).
    next: Vec<u64>,
    /// Per pixel `Σ_j b_j²/n_j(i)`: its effective sample count is planned²/this.
    spread: Vec<f64>,
    /// The first round's planned spp per replicate.
    first_planned: u64,
    /// The spp per replicate planned so far.
    planned: u64,
    /// The rounds done.
    done: u32,
    /// Of those after the first, the ones that gave every pixel the same samples.
    uniform_rounds: u32,
    /// The last round's planned size.
    last_size: u64,
    /// Path samples per second, from the last round.
    rate: f64,
}

/// The samples of one round: its planned size, each pixel's count (the same in every
/// replicate), and each replicate's film of them.
struct Round {
    size: u64,
    counts: Vec<u32>,
    films: Vec<Film>,
}

impl<F: SamplerFactory> Job<'_, F> {
    /// Adaptive rounds (see [`crate::estimate`]): round `j` gives pixel `i` the same
    /// `n_j(i) ≥ 1` samples in every replicate, a fresh set at the replicate's next sample
    /// indices, allocated from the rounds before; the image weighs round `j`'s means by its
    /// planned spp. Rounds double from `max(1, spp/(16R))` spp per replicate; with a time limit
    /// the first is `⌈pass/R⌉` (`pass` = `--pass-spp`, default 16) and each next one doubles
    /// while the time left, at the last round's samples per second, allows, else takes what it
    /// allows (at least 1); with a target error alone they stay at `⌈pass/R⌉`, checked after
    /// each. They stop at `spp` in all, the time limit (a whole round past it), the target error
    /// or the stop flag (which drops the round under way).
    pub(super) fn adaptive(&self, stats: &mut RenderStats) -> Result<Rendered> {
        let (settings, plan) = (self.settings, self.plan);
        let first = settings.first_sample as u64;
        let r64 = settings.replicates as u64;
        let first_round = self.first_round_size();
        let pixels = settings.width as usize * settings.height as usize;
        let mut s = Rounds {
            raw: Film::new(settings.width, settings.height),
            replicates: Replicates::new(settings.replicates, pixels),
            next: vec![first; pixels],
            spread: vec![0.0; pixels],
            first_planned: 0,
            planned: 0,
            done: 0,
            uniform_rounds: 0,
            last_size: first_round,
            rate: 0.0,
        };
        let mut interrupted = false;
        loop {
            let size = self.round_size(&s, first_round);
            if size == 0 {
                break;
            }
            if s.done > 0 && self.stopped() {
                interrupted = true;
                break;
            }
            // a round gives every pixel at least one sample (unbiasedness needs it): it cannot
            // run once a pixel has used the last sample index, 2³² − 1 (hot pixels take more
            // than the spp, so a render that starts near the end can get there)
            if s.next.iter().any(|&o| o >= SAMPLE_INDICES) {
                break;
            }
            let counts = match self.round_counts(&mut s, size) {
                Ok(counts) => counts,
                Err(gain) => {
                    // the first round's samples are every pixel's first planned·R: uniform
                    let (next, pilot_spp) = (first + s.planned, s.planned * r64);
                    return self.finish_uniformly(s.raw, next, pilot_spp, gain, stats);
                }
            };
            // a round that gives every pixel the same count plans that count: the first
            // round's size kept from a sliver of a grid is its size (its planned size recorded
            // the spp it did not render)
            let size = match counts.first() {
                Some(&c) if counts.iter().all(|&x| x == c) => c as u64,
                _ => size,
            };
            let round_start = Instant::now();
            let Some(round) = self.round(s.done, size, counts, &s.next, stats) else {
                interrupted = true;
                break; // a later round the stop flag cuts is dropped
            };
            let n: u64 = round.counts.iter().map(|&c| c as u64).sum::<u64>() * r64;
            s.add(round)?;
            let took = round_start.elapsed().as_secs_f64();
            if took > 0.0 {
                s.rate = n as f64 / took;
            }
            interrupted = self.stopped();
            if interrupted || plan.time_limit.is_some_and(|t| self.start.elapsed() >= t) {
                break;
            }
            if let Some(target) = plan.target_error {
                let film = weighted(&s.raw, &s.replicates);
                if ErrorEstimate::of(&s.replicates, &film).rel_mse <= target {
                    break;
                }
            }
        }
        Ok(s.rendered(settings, interrupted))
    }

    /// The first round's spp per replicate: `⌈pass/R⌉` with a pass size, a time limit or a
    /// target error (`pass` = `--pass-spp`, default 16), else `max(1, spp/(16R))`.
    fn first_round_size(&self) -> u64 {
        let (settings, plan) = (self.settings, self.plan);
        let r64 = settings.replicates as u64;
        let steady = plan.time_limit.is_some() || plan.target_error.is_some();
        match (plan.pass_spp, steady) {
            (Some(p), _) => (p as u64).div_ceil(r64),
            (None, true) => 16u64.div_ceil(r64),
            (None, false) => (settings.spp as u64 / (16 * r64)).max(1),
        }
    }

    /// The next round's planned spp per replicate (0: the spp are all planned).
    fn round_size(&self, s: &Rounds, first_round: u64) -> u64 {
        let plan = self.plan;
        let r64 = self.settings.replicates as u64;
        let steady = plan.time_limit.is_some() || plan.target_error.is_some();
        let size = if let (Some(t), true) = (plan.time_limit, s.done > 0) {
            // rounds follow the clock: double while the time left allows, else what the time
            // left can render at the last round's rate (glossy plates at 10 s: relMSE 2.2×
            // lower than uniform, against 1.3× with rounds of a fixed pass)
            let left = t.saturating_sub(self.start.elapsed()).as_secs_f64();
            let fit = (left * s.rate / (s.raw.len() as f64 * r64 as f64)) as u64;
            crate::sampler::stratifiable((2 * s.last_size).min(fit))
        } else if s.done == 0 || steady {
            first_round
        } else {
            first_round << (s.done - 1).min(40)
        };
        // the last round fills the spp exactly; at least one round runs
        let spp = self.settings.spp as u64;
        if s.done == 0 {
            size.min((spp / r64).max(1))
        } else {
            size.min(spp / r64 - s.planned.min(spp / r64))
        }
    }

    /// Each pixel's samples in the next round of `size` planned spp: all the same in the first
    /// round; after it, allocated from the estimates where their cross-validated gain says it
    /// pays, else the same again. `Err(gain)` after the first round of a render without a
    /// target error whose gain says it does not pay: the render finishes uniformly. Counts are
    /// kept from slivers of a grid and below the last sample index.
    fn round_counts(&self, s: &mut Rounds, size: u64) -> std::result::Result<Vec<u32>, f64> {
        let (w, h) = (self.settings.width, self.settings.height);
        let counts: Vec<u32> = if s.done == 0 {
            vec![size as u32; s.raw.len()]
        } else {
            let e = ErrorEstimate::of(&s.replicates, &s.raw);
            let mean = s.raw.mean_image();
            let samples = effective_samples(&s.spread, s.planned);
            let gain = estimate::cross_validated_gain(w, &mean, &e.variance, &samples);
            let bar = self.plan.min_allocation_gain;
            if gain >= bar.unwrap_or(estimate::ALLOCATE_ABOVE) {
                // the error per sample from the variance of the weighted mean and its
                // effective count (Σ counts overstated it where counts left the plan)
                estimate::allocate(w, h, &mean, &e.variance, &samples, size as u32)
            } else if s.done == 1 && self.plan.target_error.is_none() {
                return Err(gain);
            } else {
                s.uniform_rounds += 1;
                vec![size as u32; s.raw.len()]
            }
        };
        // keep every pixel's sample indices below 2³², and its set off a sliver of a grid
        Ok(counts
            .iter()
            .zip(&s.next)
            .map(|(&c, &o)| {
                let c = crate::sampler::stratifiable(c as u64);
                c.min(SAMPLE_INDICES.saturating_sub(o)).max(1) as u32
            })
            .collect())
    }

    /// Round `done` (0: the first): every replicate renders `counts` samples of each pixel
    /// from its sample index in `next`. `None` when the stop flag cut a later round (it is
    /// dropped); a cut first round becomes one sample per pixel of each replicate, rendered
    /// whole (quick), since the image needs every pixel in every replicate.
    fn round(
        &self,
        done: u32,
        size: u64,
        counts: Vec<u32>,
        next: &[u64],
        stats: &mut RenderStats,
    ) -> Option<Round> {
        let reps = self.settings.replicates;
        let (w, h) = (self.settings.width, self.settings.height);
        let render = |count: &[u32], stop, stats: &mut RenderStats| {
            let mut films = Vec::with_capacity(reps as usize);
            for rep in 0..reps {
                let samples = Samples::Own(Alloc {
                    origin: next,
                    count,
                });
                let mut f = Film::new(w, h);
                let (_, cut) = self.batch(rep, samples, stop, &mut f, stats);
                if cut {
                    return None;
                }
                films.push(f);
            }
            Some(films)
        };
        if let Some(films) = render(&counts, self.plan.stop.as_deref(), stats) {
            return Some(Round {
                size,
                counts,
                films,
            });
        }
        if done > 0 {
            return None;
        }
        let ones = vec![1u32; next.len()];
        let films = render(&ones, None, stats)?;
        Some(Round {
            size: 1,
            counts: ones,
            films,
        })
    }

    /// The rest of an adaptive render whose first round said allocating cannot pay (its
    /// cross-validated `gain` below [`estimate::ALLOCATE_ABOVE`]): uniform passes of one set of
    /// points from sample index `next` on (the first round's replicates used the indices before
    /// it), growing under a time limit as a render without `--adaptive` does, merged with the
    /// first round's `pilot_spp` samples per pixel. Every pixel holds the same samples, so the
    /// image is their plain mean; its error is the per-sample estimate of one set.
    fn finish_uniformly(
        &self,
        pilot: Film,
        next: u64,
        pilot_spp: u64,
        gain: f64,
        stats: &mut RenderStats,
    ) -> Result<Rendered> {
        let settings = RenderSettings {
            replicates: 1,
            first_sample: next as u32,
            spp: (self.settings.spp as u64 - pilot_spp).max(1) as u32,
            ..self.settings.clone()
        };
        // the rest is a size the code derives: one set of it would be a sliver of a grid
        // where it is prime or oblong (1037 − 64 = 973 = 7·139), so its first pass is kept
        // from one and a set of what is left follows
        let rest = settings.spp as u64;
        let plan = PassPlan {
            adaptive: false,
            pass_spp: (self.plan.pass_spp).or(Some(
                crate::sampler::stratifiable(rest).min(u32::MAX as u64) as u32,
            )),
            ..self.plan.clone()
        };
        let job = Job {
            settings: &settings,
            plan: &plan,
            ..*self
        };
        let rest = job.uniform(stats)?;
        let mut film = pilot;
        film.merge(&rest.film).map_err(Error::Settings)?;
        let estimate = ErrorEstimate::of(&Replicates::new(1, film.len()), &film);
        Ok(Rendered {
            film,
            stats: RenderStats::default(),
            first_sample: self.settings.first_sample,
            spp: (pilot_spp + rest.spp as u64).min(u32::MAX as u64) as u32,
            passes: std::iter::once(pilot_spp as u32)
                .chain(rest.passes)
                .collect(),
            interrupted: rest.interrupted,
            replicates: 1,
            estimate,
            rounds: Some(1),
            uniform_rounds: 0,
            finished_uniformly: Some(gain),
            allocation: None,
            ears_map: None,
        })
    }
}

impl Rounds {
    /// Add a round's samples: each replicate's means weighted by its planned size, every
    /// sample to the raw film, and each pixel's next sample index and spread moved on.
    fn add(&mut self, round: Round) -> Result<()> {
        for (rep, f) in round.films.iter().enumerate() {
            self.replicates.add_means(rep as u32, f, round.size as f64);
            self.raw.merge(f).map_err(Error::Settings)?;
        }
        let b2 = (round.size * round.size) as f64;
        for ((o, &c), q) in self
            .next
            .iter_mut()
            .zip(&round.counts)
            .zip(&mut self.spread)
        {
            *o += c as u64;
            *q += b2 / c as f64;
        }
        if self.done == 0 {
            self.first_planned = round.size;
        }
        self.planned += round.size;
        self.last_size = round.size;
        self.done += 1;
        Ok(())
    }

    /// The render these rounds made, with its error estimate and its bounds on the gain of
    /// allocating.
    fn rendered(self, settings: &RenderSettings, interrupted: bool) -> Rendered {
        let film = weighted(&self.raw, &self.replicates);
        let estimate = ErrorEstimate::of(&self.replicates, &film);
        let gains = crate::estimate::allocation_gains(
            settings.width,
            &film.mean_image(),
            &estimate.variance,
            &effective_samples(&self.spread, self.planned),
            self.first_planned as f64 / self.planned.max(1) as f64,
        );
        let r64 = settings.replicates as u64;
        Rendered {
            film,
            stats: RenderStats::default(),
            first_sample: settings.first_sample,
            spp: (self.planned * r64).min(u32::MAX as u64) as u32,
            passes: Vec::new(),
            interrupted,
            replicates: settings.replicates,
            estimate,
            rounds: Some(self.done),
            uniform_rounds: self.uniform_rounds,
            finished_uniformly: None,
            allocation: Some(gains),
            ears_map: None,
        }
    }
}

/// Each pixel's effective sample count after rounds of `planned` spp in all: `B²/Σ_j b_j²/n_j(i)`
/// from `spread` = `Σ_j b_j²/n_j(i)` (`B` for a pixel that took every round's planned size).
fn effective_samples(spread: &[f64], planned: u64) -> Vec<f64> {
    let b2 = (planned * planned) as f64;
    spread.iter().map(|&q| b2 / q.max(1e-300)).collect()
}

/// `raw`'s samples with each pixel's sum rescaled to `F·n`, `F` the replicates' weighted mean:
/// a film whose mean is an adaptive render's image (its per-sample variance is then about, not
/// exactly, the samples').
fn weighted(raw: &Film, replicates: &Replicates) -> Film {
    let mut film = raw.clone();
    for i in 0..film.len() {
        let (_, s2, n) = raw.pixel_sums(i);
        film.set_pixel_sums(i, replicates.mean(i) * n as f64, s2, n);
    }
    film
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The per-sample error `allocate` shares by is the variance of the weighted mean times the
    /// count whose plain mean has that variance, `B²/Σ_j b_j²/n_j`: two pixels whose samples
    /// have the same variance get the same share, whatever their counts were (issue 46: with
    /// `Σ_j n_j` a pixel that took 16 then 128 samples of rounds planned 16 and 32 counted 144
    /// samples, 1.5× its 96, and drew √1.5 × the share).
    #[test]
    fn allocation_reads_the_effective_count_of_weighted_rounds() {
        let sigma2 = 0.3f32;
        let mut spread = [0.0f64; 2];
        for (b, counts) in [(16u64, [16u32, 16]), (32, [32, 128])] {
            for (q, &c) in spread.iter_mut().zip(&counts) {
                *q += (b * b) as f64 / c as f64;
            }
        }
        let samples = effective_samples(&spread, 48);
        assert_eq!(samples, vec![48.0, 96.0]);
        // the weighted means' variances: σ²·Σ b_j²/n_j / B²
        let variance: Vec<Vec3> = spread
            .iter()
            .map(|q| Vec3::splat(sigma2 * (*q / (48.0 * 48.0)) as f32))
            .collect();
        let mean = [Vec3::splat(0.5); 2];
        let counts = estimate::allocate(2, 1, &mean, &variance, &samples, 64);
        assert_eq!(counts[0], counts[1], "{counts:?}");
    }
}
