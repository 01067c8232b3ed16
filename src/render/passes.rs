//! Uniform passes: every pixel the same samples, pass after pass, each pass one replicate's;
//! the stop condition (the spp, the time limit, the target error, the stop flag) read between
//! passes, and a pass the stop flag cuts replaced by every pixel's first samples of it.
//!
//! Under a time limit (one replicate, no shard, no target error) the passes grow as adaptive
//! rounds do: the first is `pass_spp`, each next one doubles while the time left allows at the
//! last pass's samples per second, else takes what the time left allows. Each pass is one
//! stratified set, and a set of N stratifies better than N/16 sets of 16 (lit-checker 128×96 at
//! 10 s: relMSE 7.9× lower with passes of 1024 than of 16).

use super::*;

/// One uniform pass: the samples `bounds` (relative to the render's first sample) of the set
/// of replicate `rep` whose first sample index is `origin`; of fixed passes, pass number `k`
/// (passes that follow the clock have one replicate, and `k` 0).
struct UniformPass {
    bounds: Range<u64>,
    k: u64,
    rep: u32,
    origin: u64,
}

/// What a pass rendered: its film, the samples per pixel it holds, the wall seconds per pixel
/// sample of the pixels it completed (if any), and whether the stop flag cut it.
struct PassOutput {
    film: Film,
    samples: u64,
    rate: Option<f64>,
    cut: bool,
}

impl<F: SamplerFactory> Job<'_, F> {
    /// Every pixel the same samples, in passes; pass `k` belongs to replicate `k mod R` and
    /// holds that replicate's sample indices `first + ⌊k/R⌋·P ..` (see [`render_passes`]).
    pub(super) fn uniform(&self, stats: &mut RenderStats) -> Result<Rendered> {
        let (settings, plan) = (self.settings, self.plan);
        let spp = settings.spp as u64;
        let reps = settings.replicates as u64;
        let pass = plan
            .pass_spp
            .map_or(spp.div_ceil(reps), |p| p as u64)
            .clamp(1, spp.max(1));
        let range = match plan.shard {
            Some(s) => {
                let r = shard_range(settings.spp, s)?;
                r.start as u64..r.end as u64
            }
            None => 0..spp,
        };
        let first = settings.first_sample as u64;
        let mut film = Film::new(settings.width, settings.height);
        let mut replicates = Replicates::new(settings.replicates, film.len());
        let mut done = range.start;
        let mut interrupted = false;
        // passes that follow the clock (see the module doc): the last one's size and rate
        let growing = plan.time_limit.is_some()
            && plan.shard.is_none()
            && plan.target_error.is_none()
            && reps == 1;
        let (mut last_size, mut rate) = (0u64, None::<f64>);
        let mut passes = Vec::new();
        while done < range.end {
            // every pass renders at least one sample per pixel (its end lies past `done`), so a
            // render stopped before its first batch still writes a sample per pixel
            if done > range.start && self.stopped() {
                interrupted = true;
                break;
            }
            let p = if growing {
                self.growing_pass(done, last_size, rate)
            } else {
                self.fixed_pass(done, pass)
            };
            let out = self.pass(&p, done..p.bounds.end.min(range.end), stats);
            rate = out.rate.or(rate);
            if !out.cut {
                last_size = out.samples;
            }
            done += out.samples;
            passes.push(out.samples as u32);
            interrupted = self.stopped() && done < range.end;
            film.merge(&out.film).map_err(Error::Settings)?;
            replicates.add_samples(p.rep, &out.film);
            if interrupted || plan.time_limit.is_some_and(|t| self.start.elapsed() >= t) {
                break;
            }
            // a target error is checked after every whole round of R passes
            if let Some(target) = plan.target_error {
                if done == p.bounds.end
                    && (p.k + 1).is_multiple_of(reps)
                    && ErrorEstimate::of(&replicates, &film).rel_mse <= target
                {
                    break;
                }
            }
        }
        let estimate = ErrorEstimate::of(&replicates, &film);
        Ok(Rendered {
            film,
            stats: RenderStats::default(),
            first_sample: (first + range.start) as u32,
            spp: (done - range.start) as u32,
            passes,
            interrupted,
            replicates: replicates.filled().max(1),
            estimate,
            rounds: None,
            uniform_rounds: 0,
            finished_uniformly: None,
            allocation: None,
            ears_map: None,
        })
    }

    /// The pass of `pass` spp that holds sample `done` (relative to the render's first sample),
    /// with the sample indices of its replicate: pass `k` is replicate `k mod R`'s pass `⌊k/R⌋`.
    fn fixed_pass(&self, done: u64, pass: u64) -> UniformPass {
        let reps = self.settings.replicates as u64;
        let bounds = pass_bounds(done, pass, self.settings.spp as u64);
        let k = bounds.start / pass;
        // the replicate's own sample indices: below first + spp ≤ 2³², so a u32
        let origin = self.settings.first_sample as u64 + k / reps * pass;
        UniformPass {
            bounds,
            k,
            rep: (k % reps) as u32,
            origin,
        }
    }

    /// The pass after `done` samples of a render whose passes follow the clock (one replicate):
    /// `pass_spp` first (no `rate` or `last_size` yet), then twice the last pass while the time
    /// left allows at `rate` wall seconds per pixel sample, else what it allows.
    fn growing_pass(&self, done: u64, last_size: u64, rate: Option<f64>) -> UniformPass {
        let (settings, plan) = (self.settings, self.plan);
        let spp = settings.spp as u64;
        let size = match (plan.time_limit, rate) {
            (Some(t), Some(rate)) if last_size > 0 => {
                let pixels = settings.width as f64 * settings.height as f64;
                let left = t.saturating_sub(self.start.elapsed()).as_secs_f64();
                let fit = (left / (rate * pixels).max(1e-12)) as u64;
                // a size the clock picks, cut to the spp left, kept from a sliver of a grid
                // (cut after the rounding, --spp 997 left a last pass of 501 = 3·167)
                let left = spp.saturating_sub(done).max(1);
                crate::sampler::stratifiable((2 * last_size).min(fit).min(left))
            }
            _ => plan.pass_spp.map_or(spp, |p| p as u64).clamp(1, spp.max(1)),
        };
        UniformPass {
            bounds: done..(done + size).min(spp),
            k: 0,
            rep: 0,
            origin: settings.first_sample as u64 + done,
        }
    }

    /// Render the samples `span` (relative to the render's first sample) of pass `p`. A pass
    /// the stop flag cuts is dropped, and every pixel's first samples of it rendered instead:
    /// one where no pixel finished before the cut (a stop before the render began), else one,
    /// timed over the whole image, then as many more as take about [`BATCH_SECONDS`] in all at
    /// that speed. (The speed of the pixels that finished before the cut is no measure: where a
    /// pass is long, they are the few quickest pixels, those that see the background or the
    /// light; on the Cornell box at 64×64 with passes of 262,144 samples that speed was 5× the
    /// image's, and a stop took 1.2 s instead of a quarter.)
    fn pass(&self, p: &UniformPass, span: Range<u64>, stats: &mut RenderStats) -> PassOutput {
        let (w, h) = (self.settings.width, self.settings.height);
        let set = SamplePass {
            origin: p.origin as u32,
            size: (p.bounds.end - p.bounds.start) as u32,
        };
        let at = |done: u64| p.origin + done - p.bounds.start;
        let samples = |from: u64, to: u64| Samples::Pass {
            set,
            range: at(span.start + from)..at(span.start + to),
        };
        let all = span.end - span.start;
        let mut film = Film::new(w, h);
        let (rate, cut) = self.batch(
            p.rep,
            samples(0, all),
            self.plan.stop.as_deref(),
            &mut film,
            stats,
        );
        if !cut {
            return PassOutput {
                film,
                samples: all,
                rate,
                cut,
            };
        }
        // a pixel's sums go on in sample order: the first sample, then the rest, are the same
        // sums as all of them in one batch
        let mut film = Film::new(w, h);
        let start = Instant::now();
        self.batch(p.rep, samples(0, 1), None, &mut film, stats);
        let one = start.elapsed().as_secs_f64();
        let n = match rate {
            None => 1,
            Some(_) => ((BATCH_SECONDS / one.max(1e-12)) as u64).clamp(1, all),
        };
        if n > 1 {
            self.batch(p.rep, samples(1, n), None, &mut film, stats);
        }
        PassOutput {
            film,
            samples: n,
            rate: Some(one / (w as f64 * h as f64)),
            cut,
        }
    }
}
