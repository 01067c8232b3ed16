//! The training of `--roulette ears` ([`crate::integrator::rrs`]): iterations of 2, 2, 4, 8 …
//! spp before the image, the first with classic roulette, each with the cache and image
//! statistics the earlier ones taught, their continuations recorded into the cache chunk by
//! chunk in a fixed order (so the cache is a function of the seed alone, whatever the
//! threads). After each iteration:
//!
//! - the pixel estimate `Î`: the mean of every training sample so far, median-filtered over
//!   3×3 pixels per channel (the paper denoises it; a median keeps a training firefly from
//!   raising its neighbours' estimates), kept as `1/√(Î² + 0.01)`;
//! - the image's factor `√(C_img/V_img)`: `C_img` the rays per camera sample of the
//!   iteration, `V_img` the mean over pixels of its sample variance over `Î² + 0.01`, the ten
//!   largest left out (the paper's outlier rejection of ten).
//!
//! The training spends at most an eighth of the render's spp (at least 4 spp: two iterations)
//! and, under a time limit, stops where the next iteration (about twice the last) would pass
//! an eighth of it. Its images are not kept: the image is rendered with the frozen cache.

use super::tile::RrsKernel;
use super::*;
use crate::integrator::rrs::{direction_bin, RrsCache, RrsLearned, RrsPath, MAX_EXTRA_BRANCHES};
use glam::Vec3;

/// What `--roulette ears` learned before the image.
pub(super) struct RrsState {
    cache: RrsCache,
    image: f32,
    pixel_norm: Vec<Vec3>,
}

impl RrsState {
    /// The factor `n` ([`RrsPath::factor`]) at the first vertex of the ray through each
    /// pixel's centre, for a path of throughput one there (row-major, `width × height`): the
    /// cache made visible, over 1 where the camera's paths split and under 1 where they end
    /// more often. 0 where the ray escapes or meets a mirror, glass or a black surface (no
    /// Phong vertex to split).
    pub(super) fn first_vertex_map(
        &self,
        scene: &Scene,
        camera: &Camera,
        (w, h): (u32, u32),
    ) -> Vec<f32> {
        let mut stack = TraceStack::default();
        let learned = self.kernel().learned;
        let mut map = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let (o, d) = camera.generate_ray(glam::UVec2::new(x, y), glam::Vec2::splat(0.5));
                let i = (y * w + x) as usize;
                let n = scene
                    .intersect(&mut stack, o, d, f32::INFINITY)
                    .map_or(0.0, |hit| {
                        let s = scene.surface(&hit);
                        let m = scene.material_at(&s);
                        let delta = m.specular.is_some_and(|d| !d.is_black());
                        if delta || scene.bsdf_at(&s).is_black() {
                            return 0.0;
                        }
                        let path = RrsPath {
                            learned,
                            pixel_norm: self.pixel_norm.get(i).copied().unwrap_or(Vec3::ONE),
                            extra: MAX_EXTRA_BRANCHES,
                            records: None,
                        };
                        path.factor(s.p, direction_bin(-d), Vec3::ONE, 1)
                    });
                map.push(n);
            }
        }
        map
    }

    /// What the tile kernel renders the image with.
    pub(super) fn kernel(&self) -> RrsKernel<'_> {
        RrsKernel {
            learned: RrsLearned {
                cache: Some(&self.cache),
                image: self.image,
            },
            pixel_norm: &self.pixel_norm,
            record: false,
        }
    }
}

impl<F: SamplerFactory> Trainer<'_, F> {
    /// The training (see the module doc), with the guide `guide` where directions are guided;
    /// its rays and thread time added to `stats`, its [`RrsStats`] set there.
    pub(super) fn train_rrs(&self, guide: Option<&Guide>, stats: &mut RenderStats) -> RrsState {
        let settings = self.settings;
        let began = Instant::now();
        let (lo, hi) = super::training::scene_bounds(self.scene);
        let mut state = RrsState {
            cache: RrsCache::new(lo, hi),
            image: 1.0,
            pixel_norm: Vec::new(),
        };
        let budget = (settings.spp as u64 / 8).max(4);
        let mut all = Film::new(settings.width, settings.height);
        let mut r = RrsStats::default();
        let mut last = Duration::ZERO;
        for k in 0u32..32 {
            let spp = if k == 0 { 2 } else { 2u64 << (k - 1) };
            if k >= 2 {
                let over_time =
                    (self.plan.time_limit).is_some_and(|t| began.elapsed() + 2 * last > t / 8);
                let stopped = (self.plan.stop)
                    .as_ref()
                    .is_some_and(|f| f.load(Ordering::Relaxed));
                if r.training_spp + spp > budget || over_time || stopped {
                    break;
                }
            }
            let t0 = Instant::now();
            let Some((film, split)) = self.rrs_iteration(k, spp, guide, &mut state, stats) else {
                break;
            };
            all.merge(&film).expect("the same size");
            self.learn_image(&film, &all, &mut state);
            r.iterations += 1;
            r.training_spp += spp;
            r.first_split = split;
            last = t0.elapsed();
        }
        r.training = began.elapsed();
        r.nodes = state.cache.len();
        r.image_factor = state.image;
        stats.rrs = Some(r);
        state
    }

    /// Iteration `k` of `spp` samples (classic roulette for `k = 0`), seed
    /// `mix64(seed ⊕ (k + 1)·c)` whatever the render's first sample or shard, its records
    /// added to the cache in tile order and the cache refined. Its film and the mean number of
    /// continuations at the first vertex; `None` when the stop flag cut it (nothing learned).
    fn rrs_iteration(
        &self,
        k: u32,
        spp: u64,
        guide: Option<&Guide>,
        state: &mut RrsState,
        stats: &mut RenderStats,
    ) -> Option<(Film, f64)> {
        let settings = self.settings;
        let seed = crate::math::mix64(
            settings.seed ^ 0x4541_5253 ^ (k as u64 + 1).wrapping_mul(0x2545_f491_4f6c_dd1d),
        );
        let set = SamplePass {
            origin: 0,
            size: spp as u32,
        };
        let mut film = Film::new(settings.width, settings.height);
        let tiles = tile_count(settings);
        // records of at most about 2^18 path samples at a time
        let per_chunk = ((1u64 << 18) / (spp * (TILE * TILE) as u64)).max(1) as u32;
        let (mut rays, mut samples, mut first) = (0u64, 0u64, 0u64);
        for start in (0..tiles).step_by(per_chunk as usize) {
            let guiding = Guiding {
                tree: guide,
                record: false,
            };
            let rrs = RrsKernel {
                learned: RrsLearned {
                    cache: (k > 0).then_some(&state.cache),
                    image: state.image,
                },
                pixel_norm: &state.pixel_norm,
                record: true,
            };
            let kernel = self.kernel(guiding, seed).with_rrs(Some(rrs));
            let batch = Batch {
                samples: Samples::Pass { set, range: 0..spp },
                tiles: start..(start + per_chunk).min(tiles),
                stop: self.plan.stop.as_deref(),
            };
            let out = kernel.render(&batch, Some(&mut film));
            stats.rays.add(&out.stats.rays);
            stats.thread_time += out.stats.thread_time;
            if out.cut {
                return None;
            }
            rays += out.stats.rays.total();
            samples += out.stats.samples;
            let records = out.rrs_records;
            first += records.iter().filter(|r| r.first).count() as u64;
            for rec in &records {
                state.cache.add(rec);
            }
        }
        state.cache.finish_iteration();
        let c_img = rays as f64 / samples.max(1) as f64;
        state.image = c_img as f32; // divided by V_img in learn_image
        Some((film, first as f64 / samples.max(1) as f64))
    }

    /// The pixel estimate from `all` (every training sample so far) and the image factor from
    /// the iteration's `film` (see the module doc); `state.image` holds `C_img` on entry.
    fn learn_image(&self, film: &Film, all: &Film, state: &mut RrsState) {
        let (w, h) = (self.settings.width as i64, self.settings.height as i64);
        let mean = all.mean_image();
        let mut norm = Vec::with_capacity(mean.len());
        let mut rel = Vec::with_capacity(mean.len());
        for y in 0..h {
            for x in 0..w {
                // the median of the 3×3 pixels around, channel by channel: a training
                // firefly does not raise its neighbours' estimates (which would send their
                // paths to roulette, and make fireflies of them)
                let mut near = [[0.0f32; 9]; 3];
                let mut n = 0;
                for (dx, dy) in (-1..=1).flat_map(|dx| (-1..=1).map(move |dy| (dx, dy))) {
                    let (u, v) = (x + dx, y + dy);
                    if (0..w).contains(&u) && (0..h).contains(&v) {
                        let m = mean[(v * w + u) as usize];
                        for c in 0..3 {
                            near[c][n] = m[c];
                        }
                        n += 1;
                    }
                }
                let est = Vec3::from_array(near.map(|mut c| {
                    c[..n].sort_unstable_by(f32::total_cmp);
                    c[n / 2]
                }));
                let d = est * est + Vec3::splat(crate::estimate::REL_EPSILON as f32);
                let i = (y * w + x) as usize;
                norm.push(d.map(|d| 1.0 / d.sqrt()));
                let var = film.sample_variance(i).as_vec3();
                rel.push(((var / d).element_sum() / 3.0) as f64);
            }
        }
        rel.retain(|v| v.is_finite());
        rel.sort_by(f64::total_cmp);
        rel.truncate(rel.len().saturating_sub(10).max(1).min(rel.len()));
        let v_img = rel.iter().sum::<f64>() / rel.len().max(1) as f64;
        let c_img = state.image as f64;
        state.image = if v_img > 0.0 && v_img.is_finite() {
            (c_img / v_img).sqrt() as f32
        } else {
            1.0
        };
        state.pixel_norm = norm;
    }
}
