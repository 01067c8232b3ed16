//! Guide training: the iterations of a guided render before its final one (doubling spp,
//! each sampling with the tree the earlier ones taught), rendered in chunks of bounded size whose
//! records reach the tree in a fixed order, so the tree is a function of the seed alone and
//! training memory does not grow with the spp.

use super::combine::{IterationImage, KeptIterations};
use super::edges::EdgeMap;
use super::gate::Gate;
use super::*;

/// What a guided render's training needs: the render's scene, camera, settings and plan, and
/// the samplers `factory` makes.
pub(super) struct Trainer<'a, F: SamplerFactory> {
    pub(super) scene: &'a Scene,
    pub(super) camera: &'a Camera,
    pub(super) settings: &'a RenderSettings,
    pub(super) plan: &'a PassPlan,
    pub(super) factory: &'a F,
    /// The image's edge pixels, where a training image's samples spend edge rays (a guide
    /// learned apart sees them too: its paths count the camera's emission as the render's own
    /// training would, so the guide is the same).
    pub(super) edges: Option<&'a EdgeMap>,
}

/// How much a guide's training may spend: its iterations' samples per pixel in all, and the wall
/// time by which the last one must be expected to end (from the start the training is given).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainingBudget {
    /// The iterations' spp in all (at least one iteration runs).
    pub spp: u64,
    /// An iteration starts only if it is expected (at the last one's speed per pixel sample) to
    /// end by then.
    pub time: Option<Duration>,
}

impl TrainingBudget {
    /// A guided render's own training: half its spp; half its time limit where the image
    /// keeps the training iterations ([`PassPlan::discard_training`]), a third where it is the
    /// final iteration alone. Measured at 10 s on the door, door-dark and the gap (three seed
    /// pairs, interleaved): keeping the training images at a third 1.13×, 1.05×, 1.22× lower
    /// relMSE than discarding them, at a half 1.30×, 1.22×, 1.16× (docs/guiding.md has the
    /// table).
    pub fn of_render(settings: &RenderSettings, plan: &PassPlan) -> TrainingBudget {
        let share = if super::keeps_training(settings, plan) {
            2
        } else {
            3
        };
        TrainingBudget {
            spp: (settings.spp as u64 / 2).max(1),
            time: plan.time_limit.map(|t| t / share),
        }
    }
}

/// A guide learned before a render, which a guided render given it ([`PassPlan::guide`])
/// samples with instead of training its own: `--strategy auto`'s guided pilot hands its guide
/// to the render it chooses.
#[derive(Clone, PartialEq)]
pub struct LearnedGuide {
    /// The guide.
    pub tree: Guide,
    /// Its training (the final iteration's time is the render's to fill in).
    pub stats: GuideStats,
}

impl std::fmt::Debug for LearnedGuide {
    /// The training and the tree's size, not the whole tree.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LearnedGuide")
            .field("stats", &self.stats)
            .field("tree", &self.tree.size())
            .finish()
    }
}

impl<'a, F: SamplerFactory> Trainer<'a, F> {
    /// The kernel a training render (the guide's or the roulette's) runs: this render's scene,
    /// camera, settings and sampler, `guide`, iteration seed `seed`, the plan's strip of tiles
    /// (a pilot's) and no progress bar.
    pub(super) fn kernel(&self, guide: Guiding<'a>, seed: u64) -> Kernel<'a, F> {
        Kernel::new(
            self.scene,
            self.camera,
            self.settings,
            self.factory,
            guide,
            &NoProgress,
        )
        .with_seed(seed)
        .with_strip(self.plan.strip.as_deref())
        .with_edges(self.edges)
    }

    /// The training iterations of a guided render (see [`crate::guiding`]): iterations of 1,
    /// 2, 4, … spp, each sampling with the tree the earlier ones taught and recording into the
    /// next, while their sum stays within `budget.spp` (at least one iteration), and while the
    /// next iteration (estimated at twice the last's time per pixel sample) would end by
    /// `budget.time` after `start`. A set stop flag ends the training. Training's rays and
    /// thread time are added to `stats`, and its [`GuideStats`] set there.
    /// With `kept`, the images of the iterations of 2 spp or more are kept there (the last
    /// [`super::combine::KEPT_ITERATIONS`] of them). With a `gate` (where the render gates:
    /// [`super::gates`]), it reads its probes at the iterations it names (kept with `kept`); a
    /// closed gate ends the training, and its verdict is in the [`GuideStats`].
    pub(super) fn train(
        &self,
        start: Instant,
        budget: TrainingBudget,
        stats: &mut RenderStats,
        mut kept: Option<&mut KeptIterations>,
        mut gate: Option<Gate>,
    ) -> Guide {
        let (lo, hi) = scene_bounds(self.scene);
        let mut tree = Guide::new(lo, hi);
        let mut g = GuideStats::default();
        let mut last = Duration::ZERO;
        // the early look's half of the first probe, and the rays it traced
        let mut half_probe: Option<(Film, u64)> = None;
        if let Some(gate) = gate.as_mut() {
            gate.first = super::gate::first_probe(self.pixels());
        }
        for k in 0u32..32 {
            let spp = 1u64 << k;
            if k > 0 && !self.starts(budget, start, last, g.training_spp + spp) {
                break;
            }
            let began = Instant::now();
            let keep = kept.is_some() && spp >= 2;
            let probing = gate.as_ref().is_some_and(|g| g.probes_at(k, self.pixels()));
            let early = gate
                .as_ref()
                .is_some_and(|g| g.looks_early_at(k, self.pixels()));
            let rays_before = stats.rays.total();
            let Some(film) = self.iteration(k, &mut tree, stats, keep || probing || early) else {
                break;
            };
            let guided_rays = stats.rays.total() - rays_before;
            // the next iteration's estimate reads this one's time, not its probe's
            let took = began.elapsed();
            let image = film.as_ref().map(IterationImage::of);
            if let (Some(kept), Some(image)) = (kept.as_deref_mut().filter(|_| keep), &image) {
                kept.push(image.clone());
            }
            let per_sample = |rays: u64| rays as f64 / (spp * self.pixels()) as f64;
            if let (Some(gate), Some(image)) = (gate.as_mut().filter(|_| early), &image) {
                let Some(half) = self.look_early(k, gate, (image, per_sample(guided_rays)), stats)
                else {
                    break; // the stop flag cut the probe: dropped, and training ends
                };
                half_probe = Some(half);
            }
            let closed = gate.as_ref().is_some_and(Gate::closed);
            if let (Some(gate), Some(image)) = (gate.as_mut().filter(|_| probing && !closed), image)
            {
                let Some((probe, probe_rays)) = self.probe(k, half_probe.take(), stats) else {
                    break; // the stop flag cut the probe: dropped, and training ends
                };
                gate.read(
                    k,
                    (&image, per_sample(guided_rays)),
                    (&probe, per_sample(probe_rays)),
                    self.settings.width as usize,
                );
                if let Some(kept) = kept.as_deref_mut() {
                    kept.push_probe(probe);
                }
            }
            g.iterations += 1;
            g.training_spp += spp;
            if gate.as_ref().is_some_and(Gate::closed) {
                break; // the rest renders with Phong directions
            }
            last = took;
        }
        g.training = start.elapsed();
        g.gate = gate;
        stats.guide = Some(g);
        tree
    }

    /// Training iteration `k`: `2^k` spp sampled with `tree` and recorded into it, chunk by
    /// chunk in a fixed order, then the tree refined for the next iteration. It uses seed
    /// `mix64(seed ⊕ (k + 1)·φ)`, whatever the render's first sample or shard: every shard of a
    /// render learns the same tree. `None` when the stop flag cut it (its last chunk's records
    /// dropped, the tree not refined); else its film where `image` asks for one.
    fn iteration(
        &self,
        k: u32,
        tree: &mut Guide,
        stats: &mut RenderStats,
        image: bool,
    ) -> Option<Option<Film>> {
        let settings = self.settings;
        let spp = 1u64 << k;
        let seed =
            crate::math::mix64(settings.seed ^ (k as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let set = SamplePass {
            origin: 0,
            size: spp as u32,
        };
        let (mut sum, mut n_samples) = (glam::DVec3::ZERO, 0u64);
        let mut film = image.then(|| Film::new(settings.width, settings.height));
        // a chunk's records are added to the tree while the next chunk renders
        let mut pending: Vec<Vec<Record>> = Vec::new();
        for (tiles, samples) in training_chunks(tile_count(settings), spp) {
            let pieces = sample_pieces(&tiles, samples);
            let results: Vec<BatchOutput> =
                tree.add_records_during(std::mem::take(&mut pending), |tree| {
                    let guide = Guiding {
                        tree: Some(tree),
                        record: true,
                    };
                    let kernel = self.kernel(guide, seed);
                    pieces
                        .into_par_iter()
                        .map(|range| {
                            let batch = Batch {
                                samples: Samples::Pass { set, range },
                                tiles: tiles.clone(),
                                stop: self.plan.stop.as_deref(),
                            };
                            kernel.render(&batch, None)
                        })
                        .collect()
                });
            if results.iter().any(|r| r.cut) {
                return None; // a cut chunk's records are dropped, and training ends
            }
            // piece by piece, in order: a leaf sees the records in the same order as from
            // their concatenation, without a copy of them all
            for r in results {
                sum += r.total;
                n_samples += r.stats.samples;
                stats.rays.add(&r.stats.rays);
                stats.thread_time += r.stats.thread_time;
                if let Some(film) = film.as_mut() {
                    for t in &r.tile_sums {
                        t.add_to(film);
                    }
                }
                pending.extend(r.records);
            }
        }
        tree.add_records_during(pending, |_| ());
        tree.finish_iteration(spp * settings.width as u64 * settings.height as u64);
        if n_samples > 0 {
            tree.set_image_mean(crate::math::luminance((sum / n_samples as f64).as_vec3()));
        }
        Some(film)
    }

    /// Pixels of the image.
    fn pixels(&self) -> u64 {
        self.settings.width as u64 * self.settings.height as u64
    }

    /// Whether the next training iteration starts: the training's spp with it (`spp`) within
    /// the budget's, its time expected (twice the `last` one's, begun at `start`) within the
    /// budget's, and no stop asked for.
    fn starts(&self, budget: TrainingBudget, start: Instant, last: Duration, spp: u64) -> bool {
        let over_time = budget.time.is_some_and(|t| start.elapsed() + 2 * last > t);
        let stopped = (self.plan.stop.as_ref()).is_some_and(|f| f.load(Ordering::Relaxed));
        spp <= budget.spp && !over_time && !stopped
    }

    /// The gate's early look at iteration `k`'s image (with the rays its paths traced per pixel
    /// sample): the first half of the next iteration's probe rendered and read against it
    /// ([`Gate::look_early`]); the half's film and rays, which that probe completes, or `None`
    /// where the stop flag cut it.
    fn look_early(
        &self,
        k: u32,
        gate: &mut Gate,
        guided: (&IterationImage, f64),
        stats: &mut RenderStats,
    ) -> Option<(Film, u64)> {
        let spp = 1u64 << k;
        let mut film = Film::new(self.settings.width, self.settings.height);
        let rays = self.probe_samples(k + 1, 0..spp, &mut film, stats)?;
        let per_sample = rays as f64 / (spp * self.pixels()) as f64;
        let half = (&IterationImage::of(&film), per_sample);
        gate.look_early(k, guided, half, self.settings.width as usize);
        Some((film, rays))
    }

    /// The gate's probe of training iteration `k` ([`super::gate`]): `2^k` spp with the guide off
    /// and without path reuse (as the training iterations render), on seeds of its own (`mix64` of
    /// the iteration's seed input with a constant of its own); its image and the rays it traced
    /// (added to `stats` with its thread time), or `None` where the stop flag cut it. Given
    /// `half`, the film and rays of its first `2^(k−1)` spp (the gate's early look), it renders
    /// the rest into that film.
    fn probe(
        &self,
        k: u32,
        half: Option<(Film, u64)>,
        stats: &mut RenderStats,
    ) -> Option<(IterationImage, u64)> {
        let spp = 1u64 << k;
        let (mut film, rays, from) = match half {
            Some((film, rays)) => (film, rays, spp / 2),
            None => (Film::new(self.settings.width, self.settings.height), 0, 0),
        };
        let more = self.probe_samples(k, from..spp, &mut film, stats)?;
        Some((IterationImage::of(&film), rays + more))
    }

    /// The samples `range` of probe `k`'s `2^k` spp ([`Trainer::probe`]) added to `film`: the
    /// rays they traced (added to `stats` with the thread time), or `None` where the stop flag
    /// cut them.
    fn probe_samples(
        &self,
        k: u32,
        range: Range<u64>,
        film: &mut Film,
        stats: &mut RenderStats,
    ) -> Option<u64> {
        let settings = self.settings;
        let seed = crate::math::mix64(
            settings.seed ^ (k as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x5bd1_e995,
        );
        let guide = Guiding {
            tree: None,
            record: false,
        };
        let kernel = self.kernel(guide, seed).unguided().without_reuse();
        let batch = Batch {
            samples: Samples::Pass {
                set: SamplePass {
                    origin: 0,
                    size: 1u32 << k,
                },
                range,
            },
            tiles: 0..tile_count(settings),
            stop: self.plan.stop.as_deref(),
        };
        let out = kernel.render(&batch, Some(film));
        stats.rays.add(&out.stats.rays);
        stats.thread_time += out.stats.thread_time;
        (!out.cut).then(|| out.stats.rays.total())
    }
}

/// Path samples a training chunk renders at most: its records (about 16 bytes per bounce)
/// are the training's memory, at most `16 B × max depth × 2¹⁸` (40 MiB at depth 10, twice
/// that while a piece is sorted into the tree) whatever the spp and the image size.
const TRAINING_CHUNK: u64 = 1 << 18;

/// The chunks of a training iteration of `spp` samples per pixel over `tiles` tiles, in the
/// order their records reach the tree: runs of whole tiles with all their samples while a
/// tile's samples fit in [`TRAINING_CHUNK`], else each tile in slices of samples. The split
/// depends on the image and the spp only, so the tree is the same for any thread count.
fn training_chunks(tiles: u32, spp: u64) -> Vec<(Range<u32>, Range<u64>)> {
    let per_tile = spp * (TILE * TILE) as u64;
    if per_tile <= TRAINING_CHUNK {
        let n = (TRAINING_CHUNK / per_tile) as u32;
        (0..tiles)
            .step_by(n as usize)
            .map(|t| (t..(t + n).min(tiles), 0..spp))
            .collect()
    } else {
        let slice = TRAINING_CHUNK / (TILE * TILE) as u64;
        (0..tiles)
            .flat_map(|t| {
                (0..spp)
                    .step_by(slice as usize)
                    .map(move |s| (t..t + 1, s..(s + slice).min(spp)))
            })
            .collect()
    }
}

/// A chunk of fewer than 8 tiles is rendered as 8 consecutive slices of its samples side by
/// side (threads work over tiles, so a chunk of one tile kept one core busy); their records
/// follow in slice order. A fixed count, not the threads', keeps the tree thread-independent.
fn sample_pieces(tiles: &Range<u32>, samples: Range<u64>) -> Vec<Range<u64>> {
    const PIECES: u64 = 8;
    let n = samples.end - samples.start;
    if tiles.len() >= PIECES as usize || n < 2 {
        return vec![samples];
    }
    let k = PIECES.min(n);
    (0..k)
        .map(|i| samples.start + n * i / k..samples.start + n * (i + 1) / k)
        .collect()
}

/// The guide a guided render of `scene` with `settings` learns before its final iteration (the
/// same seeds and budget: the same tree), with the training's stats.
pub fn learn_guide(scene: &Scene, settings: &RenderSettings) -> Result<(Guide, RenderStats)> {
    let plan = PassPlan::default();
    learn_guide_with(
        scene,
        settings,
        &plan,
        TrainingBudget::of_render(settings, &plan),
    )
}

/// The guide a guided render of `scene` with `settings` and `plan` (its strip, its stop flag)
/// learns within `budget`, with the training's stats: the iterations of [`learn_guide`], with
/// a budget of the caller's.
pub fn learn_guide_with(
    scene: &Scene,
    settings: &RenderSettings,
    plan: &PassPlan,
    budget: TrainingBudget,
) -> Result<(Guide, RenderStats)> {
    let camera = strip_camera(scene, settings, plan)?;
    with_threads(settings.threads, || {
        let mut stats = RenderStats::default();
        let start = Instant::now();
        // the edge pixels the render's own training would see (the plan's where it hands a
        // map, as `--strategy auto`'s pilots do): the same guide, bit for bit
        let edges = super::edges::of_plan(scene, &camera, settings, plan);
        struct Train<'a>(
            &'a Scene,
            &'a Camera,
            &'a RenderSettings,
            &'a PassPlan,
            TrainingBudget,
            Instant,
            &'a mut RenderStats,
            Option<&'a EdgeMap>,
        );
        impl WithSampler for Train<'_> {
            type Out = Guide;
            fn run<F: SamplerFactory>(self, factory: &F) -> Guide {
                let trainer = Trainer {
                    scene: self.0,
                    camera: self.1,
                    settings: self.2,
                    plan: self.3,
                    factory,
                    edges: self.7,
                };
                trainer.train(self.5, self.4, self.6, None, None)
            }
        }
        let work = Train(
            scene,
            &camera,
            settings,
            plan,
            budget,
            start,
            &mut stats,
            edges.as_deref(),
        );
        let tree = with_sampler(settings.strategy.sampler, work);
        stats.elapsed = start.elapsed();
        (tree, stats)
    })
}

/// The bounding box of the scene's triangles.
pub(super) fn scene_bounds(scene: &Scene) -> (glam::Vec3, glam::Vec3) {
    let (mut lo, mut hi) = (
        glam::Vec3::splat(f32::INFINITY),
        glam::Vec3::splat(-f32::INFINITY),
    );
    for prim in 0..scene.accel.len() as u32 {
        for v in scene.accel.vertices(prim) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if lo.cmple(hi).all() {
        (lo, hi)
    } else {
        (glam::Vec3::ZERO, glam::Vec3::ONE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Guided training's memory is bounded whatever the spp (issue 34: a 16×16 door at 262,144
    /// spp peaked at 1.9 GB): every chunk renders at most `TRAINING_CHUNK` path samples, the
    /// chunks cover every (tile, sample) once in order, and a chunk of few tiles is split into
    /// slices of samples that run side by side (one tile kept one core busy) and cover it.
    #[test]
    fn training_chunks_bound_the_records_and_cover_every_sample() {
        for tiles in [1u32, 3, 7, 8, 9, 192, 8100] {
            for k in [0u32, 4, 9, 10, 12, 13, 16, 18] {
                let spp = 1u64 << k;
                let chunks = training_chunks(tiles, spp);
                let mut covered = 0u64;
                let mut last = (0u32, 0u64);
                for (t, s) in &chunks {
                    let n = t.len() as u64 * (s.end - s.start) * (TILE * TILE) as u64;
                    assert!(n <= TRAINING_CHUNK, "{n} path samples in a chunk");
                    assert!((t.start, s.start) >= last, "chunks in order");
                    last = (t.start, s.start);
                    let pieces = sample_pieces(t, s.clone());
                    assert_eq!(pieces.first().unwrap().start, s.start);
                    assert_eq!(pieces.last().unwrap().end, s.end);
                    assert!(pieces.windows(2).all(|w| w[0].end == w[1].start));
                    assert!(t.len() >= 8 || s.end - s.start < 2 || pieces.len() == 8);
                    covered += t.len() as u64 * (s.end - s.start);
                }
                assert_eq!(covered, tiles as u64 * spp, "{tiles} tiles at {spp} spp");
            }
        }
    }
}
