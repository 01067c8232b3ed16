//! Uniform passes: every pixel the same samples, pass after pass, each pass one replicate's;
//! the stop condition (the spp, the time limit, the target error, the stop flag) read between
//! passes, and a pass the stop flag cuts replaced by every pixel's first samples of it.

use super::*;

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
        let pixels = settings.width as f64 * settings.height as f64;
        let mut film = Film::new(settings.width, settings.height);
        let mut replicates = Replicates::new(settings.replicates, film.len());
        let mut done = range.start;
        let mut interrupted = false;
        while done < range.end {
            // every pass renders at least one sample per pixel (its end lies past `done`), so a
            // render stopped before its first batch still writes a sample per pixel
            if done > range.start && self.stopped() {
                interrupted = true;
                break;
            }
            let bounds = pass_bounds(done, pass, spp);
            let k = bounds.start / pass;
            let rep = (k % reps) as u32;
            // the replicate's own sample indices: below first + spp ≤ 2³², so a u32
            let origin = first + k / reps * pass;
            let set = SamplePass {
                origin: origin as u32,
                size: (bounds.end - bounds.start) as u32,
            };
            let end = bounds.end.min(range.end);
            let at = |done: u64| origin + done - bounds.start;
            let mut pass_film = Film::new(settings.width, settings.height);
            if plan.stop.is_none() {
                self.batch(
                    rep,
                    (set, at(done)..at(end), None, None),
                    &mut pass_film,
                    stats,
                );
                done = end;
            } else {
                let (rate, cut) = self.batch(
                    rep,
                    (set, at(done)..at(end), plan.stop, None),
                    &mut pass_film,
                    stats,
                );
                if !cut {
                    done = end;
                } else {
                    // stopped inside the pass: drop it, take every pixel's first samples of it
                    // instead (one when no pixel finished, so no rate is known)
                    let n = rate.map_or(1, |r| (BATCH_SECONDS / (r * pixels).max(1e-12)) as u64);
                    let n = n.clamp(1, end - done);
                    pass_film = Film::new(settings.width, settings.height);
                    self.batch(
                        rep,
                        (set, at(done)..at(done + n), None, None),
                        &mut pass_film,
                        stats,
                    );
                    done += n;
                }
                interrupted = self.stopped() && done < range.end;
            }
            film.merge(&pass_film).map_err(Error::Settings)?;
            replicates.add_samples(rep, &pass_film);
            if interrupted || plan.time_limit.is_some_and(|t| self.start.elapsed() >= t) {
                break;
            }
            // a target error is checked after every whole round of R passes
            if let Some(target) = plan.target_error {
                if done == bounds.end
                    && (k + 1).is_multiple_of(reps)
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
            interrupted,
            estimate,
            rounds: None,
            allocation: None,
        })
    }
}
