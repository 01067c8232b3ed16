//! The tile kernel: rayon over 16×16 tiles; per pixel its samples, in index order, through the
//! integrator into the pixel's sums (a pass's range, or in an adaptive round the pixel's own
//! set), with the stop flag read between pixels and every 256 samples of one. With path reuse a
//! tile is rendered sample by sample instead (`tile::reused`).

use super::edges::{seen_by_edge_rays, EdgeMap};
use super::*;
use crate::integrator::rrs::{RrsLearned, RrsPath, RrsRecord, MAX_EXTRA_BRANCHES};
use crate::integrator::{radiance_rrs, radiance_split};
use glam::Vec3;

mod reused;

/// One tile's work: its pixels' sums and counters, and the traversal stack its rays use.
struct Tile {
    origin: UVec2,
    size: UVec2,
    sums: Vec<(DVec3, DVec3, u64)>,
    rays: RayCounts,
    samples: u64,
    nonfinite: u64,
    time: Duration,
    /// Whether the stop flag ended the tile before its last pixel.
    cut: bool,
    /// Its paths' guiding records, in sample order (training iterations only).
    records: Vec<Record>,
    /// Its paths' continuations under `--roulette ears`, in sample order (its training only).
    rrs_records: Vec<RrsRecord>,
    stack: TraceStack,
}

/// The number of tiles of a `settings`-sized image.
pub(super) fn tile_count(settings: &RenderSettings) -> u32 {
    settings.width.div_ceil(TILE) * settings.height.div_ceil(TILE)
}

/// Per-pixel sample sets of an adaptive round: pixel `i` renders the set of `count[i]` samples
/// with sample indices `origin[i] ..` (row-major, whole image).
#[derive(Clone, Copy)]
pub(super) struct Alloc<'a> {
    pub(super) origin: &'a [u64],
    pub(super) count: &'a [u32],
}

/// Which samples of each pixel a batch renders.
#[derive(Clone)]
pub(super) enum Samples<'a> {
    /// The sample indices `range` (all within `set`) of the set `set`, for every pixel.
    Pass { set: SamplePass, range: Range<u64> },
    /// Each pixel its own set (an adaptive round).
    Own(Alloc<'a>),
}

/// A batch of the tile kernel: which samples, of which tiles (row-major tile indices), and the
/// stop flag it reads (`None`: it runs to its end).
#[derive(Clone)]
pub(super) struct Batch<'a> {
    pub(super) samples: Samples<'a>,
    pub(super) tiles: Range<u32>,
    pub(super) stop: Option<&'a AtomicBool>,
}

/// What a batch made.
pub(super) struct BatchOutput {
    /// What it cost.
    pub(super) stats: RenderStats,
    /// Whether the stop flag left some pixel out (the film then holds a partial batch, for the
    /// caller to drop).
    pub(super) cut: bool,
    /// The paths' guiding records, each tile's in sample order, the tiles in order (when the
    /// guide records; kept per tile, not concatenated after the parallel tiles while the
    /// other threads wait: the tree groups them by leaf anyway).
    pub(super) records: Vec<Vec<Record>>,
    /// The continuations of `--roulette ears`, tile by tile in sample order (when it records).
    pub(super) rrs_records: Vec<RrsRecord>,
    /// What the samples added to the pixels' sums (a render without a film only).
    pub(super) total: DVec3,
    /// The tiles' pixel sums from zero (a render without a film only), in tile order.
    pub(super) tile_sums: Vec<TileSums>,
}

/// One tile's pixel sums (Σ L, Σ L², count), row by row from its corner `origin`, `width`
/// pixels a row.
pub(super) struct TileSums {
    pub(super) origin: UVec2,
    pub(super) width: u32,
    pub(super) sums: Vec<(DVec3, DVec3, u64)>,
}

impl TileSums {
    /// Add the sums to `film`'s pixels.
    pub(super) fn add_to(&self, film: &mut Film) {
        for (k, &(s, s2, n)) in self.sums.iter().enumerate() {
            let (x, y) = (
                self.origin.x + k as u32 % self.width,
                self.origin.y + k as u32 / self.width,
            );
            film.add_pixel_sums(film.index(x, y), s, s2, n);
        }
    }
}

/// What the tile kernel renders with: the scene seen by the camera at `width × height`, what the
/// integrator is told, the samplers `factory` makes with seed `seed`, the guide, and a progress
/// to advance. It keeps only these of the render's settings, so a job that changes the others
/// (the spp, the first sample, the replicates) cannot leave it reading stale ones.
pub(super) struct Kernel<'a, F: SamplerFactory> {
    scene: &'a Scene,
    camera: &'a Camera,
    width: u32,
    height: u32,
    integrator: IntegratorSettings,
    /// The same without the camera ray's emission: an edge pixel's paths ([`super::edges`]).
    integrator_edge: IntegratorSettings,
    factory: &'a F,
    guide: Guiding<'a>,
    progress: &'a dyn Progress,
    seed: u64,
    /// The side of the blocks whose pixels reuse each other's paths (1: none).
    reuse: u32,
    /// The learned roulette and splitting of `--roulette ears` (`None`: classic roulette).
    rrs: Option<RrsKernel<'a>>,
    /// The image's tiles the render's pixels show (`None`: the render is the image).
    strip: Option<&'a TileStrip>,
    /// The image's edge pixels and the edge rays a sample spends in each (`None`: none).
    edges: Option<&'a EdgeMap>,
}

/// What the tile kernel gives `--roulette ears`'s paths: the learned factors, each pixel's
/// `1/√(Î² + 0.01)` (row-major; empty: one, in the first training iteration), and whether the
/// continuations are recorded (training).
#[derive(Clone, Copy)]
pub(super) struct RrsKernel<'a> {
    pub(super) learned: RrsLearned<'a>,
    pub(super) pixel_norm: &'a [Vec3],
    pub(super) record: bool,
}

impl<F: SamplerFactory> Clone for Kernel<'_, F> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<F: SamplerFactory> Copy for Kernel<'_, F> {}

/// A pixel's running sums: Σ L, Σ L², and the finite samples' count.
type Sums = (DVec3, DVec3, u64);

impl<'a, F: SamplerFactory> Kernel<'a, F> {
    /// The kernel of a render of `scene` through `camera` with `settings` (and its seed).
    pub(super) fn new(
        scene: &'a Scene,
        camera: &'a Camera,
        settings: &RenderSettings,
        factory: &'a F,
        guide: Guiding<'a>,
        progress: &'a dyn Progress,
    ) -> Self {
        Kernel {
            scene,
            camera,
            width: settings.width,
            height: settings.height,
            integrator: settings.integrator(),
            integrator_edge: IntegratorSettings {
                camera_emission: false,
                ..settings.integrator()
            },
            factory,
            guide,
            progress,
            seed: settings.seed,
            reuse: settings.reuse,
            rrs: None,
            strip: None,
            edges: None,
        }
    }

    /// The same kernel without its guide: Phong directions where it guided (a guided render
    /// whose gate closed, and the gate's probes: [`super::gate`]), so its paths draw and cost
    /// what a `--directions phong` render's do.
    pub(super) fn unguided(self) -> Self {
        let phong = |mut i: IntegratorSettings| {
            if i.directions == Directions::Guided {
                i.directions = Directions::Phong;
            }
            i
        };
        Kernel {
            integrator: phong(self.integrator),
            integrator_edge: phong(self.integrator_edge),
            guide: Guiding {
                tree: None,
                record: false,
            },
            ..self
        }
    }

    /// The same kernel without path reuse (blocks of one pixel).
    pub(super) fn without_reuse(self) -> Self {
        Kernel { reuse: 1, ..self }
    }

    /// The same kernel with edge rays: as many as `map` says in each of its edge pixels
    /// (`None`: none).
    pub(super) fn with_edges(self, edges: Option<&'a EdgeMap>) -> Self {
        Kernel { edges, ..self }
    }

    /// How `pixel` (the render's) is sampled: its paths' integrator settings, and the edge rays
    /// a sample spends there (0: none) with the image's pixel they look through.
    #[inline]
    fn edge_rays(&self, pixel: UVec2) -> (&IntegratorSettings, u32, UVec2) {
        let image = self.strip.map_or(pixel, |s| s.image_pixel(pixel));
        match self.edges.map_or(0, |map| map.at(image)) {
            0 => (&self.integrator, 0, image),
            m => (&self.integrator_edge, m, image),
        }
    }

    /// What the edge rays of sample `index` see in the image's pixel `image` (`m` of them;
    /// zero when `m` is 0), counted in `rays`.
    #[inline]
    fn seen(
        &self,
        image: UVec2,
        index: u64,
        m: u32,
        rays: &mut RayCounts,
        stack: &mut TraceStack,
    ) -> Vec3 {
        if m == 0 {
            return Vec3::ZERO;
        }
        let e = seen_by_edge_rays(
            self.scene,
            self.camera,
            image,
            (self.seed, index, m),
            rays,
            stack,
        );
        rays.mark(crate::integrator::Phase::Camera);
        e
    }

    /// The same kernel rendering the tiles of `strip` (if any) side by side.
    pub(super) fn with_strip(self, strip: Option<&'a TileStrip>) -> Self {
        Kernel { strip, ..self }
    }

    /// The same kernel with `--roulette ears`'s learned factors.
    pub(super) fn with_rrs(self, rrs: Option<RrsKernel<'a>>) -> Self {
        Kernel { rrs, ..self }
    }

    /// The same kernel with the samplers of seed `seed` (a replicate's, a training iteration's).
    pub(super) fn with_seed(self, seed: u64) -> Self {
        Kernel { seed, ..self }
    }

    /// Render `batch` (sample indices below [`SAMPLE_INDICES`]) into `film`, going on from the
    /// sums it holds, on the current rayon pool; without a film, from zero sums, keeping only
    /// what the samples added (training). With a stop flag, a tile reads it before each pixel
    /// (and every 256 samples of one) and ends there when it is set.
    pub(super) fn render(&self, batch: &Batch, film: Option<&mut Film>) -> BatchOutput {
        let start = Instant::now();
        let sums = film.as_deref();
        // one sampler for the pass, cloned per worker; an adaptive round makes one per pixel.
        // The workers take the tiles one at a time ([`tiles_in_order`]).
        let set = match &batch.samples {
            Samples::Pass { set, .. } => *set,
            Samples::Own(_) => SamplePass { origin: 0, size: 1 },
        };
        let sampler = self.factory.make(self.seed, set);
        // training paths record their own bounces: they are not reused
        let k = if self.guide.record { 1 } else { self.reuse };
        let tiles: Vec<Tile> = if k > 1 {
            // one sampler per pixel of a tile, each kept on its pixel (a stratified sampler's
            // tables are per pixel)
            let samplers = vec![sampler; (TILE * TILE) as usize];
            tiles_in_order(
                batch.tiles.clone(),
                || samplers.clone(),
                |s, t| self.tile_reused(t, k, batch, sums, s),
            )
        } else {
            tiles_in_order(
                batch.tiles.clone(),
                || sampler.clone(),
                |s, t| self.tile(t, batch, sums, s),
            )
        };
        let mut out = gather(tiles, film);
        out.stats.elapsed = start.elapsed();
        out
    }

    /// Tile `t` of the image: empty, its pixels' sums to come.
    fn empty_tile(&self, t: u32) -> Tile {
        let (width, height) = (self.width, self.height);
        let tiles_x = width.div_ceil(TILE);
        let origin = UVec2::new((t % tiles_x) * TILE, (t / tiles_x) * TILE);
        let size = UVec2::new(TILE.min(width - origin.x), TILE.min(height - origin.y));
        Tile {
            origin,
            size,
            sums: Vec::with_capacity((size.x * size.y) as usize),
            rays: RayCounts::default(),
            samples: 0,
            nonfinite: 0,
            time: Duration::ZERO,
            cut: false,
            records: Vec::new(),
            rrs_records: Vec::new(),
            stack: TraceStack::default(),
        }
    }

    /// Tile `t` of `batch`, its pixels in row order, each from its sums in `sums` (if any).
    fn tile(&self, t: u32, batch: &Batch, sums: Option<&Film>, sampler: &mut F::Sampler) -> Tile {
        let tile_start = Instant::now();
        let width = self.width;
        let mut tile = self.empty_tile(t);
        let (origin, size) = (tile.origin, tile.size);
        'pixels: for y in origin.y..origin.y + size.y {
            for x in origin.x..origin.x + size.x {
                if batch.stop.is_some_and(|f| f.load(Ordering::Relaxed)) {
                    tile.cut = true;
                    break 'pixels;
                }
                let i = (y * width + x) as usize;
                let range = match &batch.samples {
                    Samples::Pass { range, .. } => range.clone(),
                    Samples::Own(a) => {
                        let set = SamplePass {
                            origin: a.origin[i] as u32,
                            size: a.count[i],
                        };
                        *sampler = self.factory.make(self.seed, set);
                        a.origin[i]..a.origin[i] + a.count[i] as u64
                    }
                };
                let from = sums.map_or((DVec3::ZERO, DVec3::ZERO, 0), |f| f.pixel_sums(i));
                let pixel = UVec2::new(x, y);
                let Some(s) = self.pixel(pixel, range, from, batch.stop, sampler, &mut tile) else {
                    tile.cut = true;
                    break 'pixels;
                };
                tile.sums.push(s);
            }
        }
        self.progress.advance(tile.samples);
        tile.time = tile_start.elapsed();
        tile
    }

    /// Start sample `index` of `pixel` on `sampler` and give its camera ray, counted in `rays`
    /// (a path starts, and its camera phase ends).
    #[inline(always)]
    fn camera_ray(
        &self,
        pixel: UVec2,
        index: u64,
        sampler: &mut F::Sampler,
        rays: &mut RayCounts,
    ) -> (Vec3, Vec3) {
        rays.start_path(self.integrator.time_traces);
        let pixel = self.strip.map_or(pixel, |s| s.image_pixel(pixel));
        // below SAMPLE_INDICES (checked by camera_for): a u32
        sampler.start_pixel_sample(pixel, index as u32);
        let ray = self
            .camera
            .generate_ray(pixel, CameraSample::draw(sampler).pixel);
        rays.mark(crate::integrator::Phase::Camera);
        ray
    }

    /// The samples `range` of `pixel`, in index order, added to its sums `from`; `None` when
    /// the stop flag (read every 256 samples) cut it. Rays, samples and non-finite samples are
    /// counted in `tile`, and guiding records appended there when the guide records.
    #[inline]
    fn pixel(
        &self,
        pixel: UVec2,
        range: Range<u64>,
        from: Sums,
        stop: Option<&AtomicBool>,
        sampler: &mut F::Sampler,
        tile: &mut Tile,
    ) -> Option<Sums> {
        let (mut sum, mut sum_sq, mut n) = from;
        let (integrator, m, image) = self.edge_rays(pixel);
        for index in range.clone() {
            // a long pixel reads the flag too (every 256 samples: a relaxed load)
            if index % 256 == 255 && stop.is_some_and(|f| f.load(Ordering::Relaxed)) {
                return None;
            }
            let ray = self.camera_ray(pixel, index, sampler, &mut tile.rays);
            let l = if let Some(r) = &self.rrs {
                let i = (pixel.y * self.width + pixel.x) as usize;
                let mut path = RrsPath {
                    learned: r.learned,
                    pixel_norm: r.pixel_norm.get(i).copied().unwrap_or(Vec3::ONE),
                    extra: MAX_EXTRA_BRANCHES,
                    records: r.record.then_some(&mut tile.rrs_records),
                };
                let (rays, stack) = (&mut tile.rays, &mut tile.stack);
                let guide = self.guide.tree;
                radiance_rrs(
                    self.scene, ray, sampler, integrator, rays, stack, guide, &mut path,
                )
            } else {
                radiance_guided(
                    self.scene,
                    ray,
                    sampler,
                    integrator,
                    &mut tile.rays,
                    &mut tile.stack,
                    self.guide.tree,
                    self.guide.record.then_some(&mut tile.records),
                )
            };
            let l = l + self.seen(image, index, m, &mut tile.rays, &mut tile.stack);
            if l.is_finite() {
                let v = l.as_dvec3();
                sum += v;
                sum_sq += v * v;
                n += 1;
            } else {
                tile.nonfinite += 1;
            }
            tile.rays.end_path();
        }
        tile.samples += range.end - range.start;
        Some((sum, sum_sq, n))
    }
}

/// `work(state, t)` for every tile `t` of `tiles`, in tile order: each worker of the pool makes
/// its `state` once (`make`: a sampler, or one per pixel of a tile) and takes the next tile from a
/// shared counter until none is left. A tile at a time, no core waits while the other ends a
/// run of tiles (rayon's own split of the range left leaves of many tiles that no thief can
/// split: Mitsuba's box on 2 threads kept 183–185% of the CPU busy, 196–198% now; 256 spp
/// 6.84 → 6.31–6.41 s), and no state is remade per tile (a state per tile, rayon's jobs of one
/// tile, cost path reuse, whose state is a sampler per pixel, 0.14 s of system time on the
/// Cornell box; with the counter `--reuse 4` there takes 0.96× the wall time, 15 pairs). Which
/// worker renders a tile changes nothing in it: the images are the same bits.
fn tiles_in_order<S, T: Send>(
    tiles: Range<u32>,
    make: impl Fn() -> S + Sync,
    work: impl Fn(&mut S, u32) -> T + Sync,
) -> Vec<T> {
    let next = std::sync::atomic::AtomicU32::new(tiles.start);
    let workers = rayon::current_num_threads().clamp(1, tiles.len().max(1));
    let mut done: Vec<(u32, T)> = (0..workers)
        .into_par_iter()
        .flat_map_iter(|_| {
            let (mut state, mut out) = (make(), Vec::new());
            loop {
                let t = next.fetch_add(1, Ordering::Relaxed);
                if t >= tiles.end {
                    break out;
                }
                out.push((t, work(&mut state, t)));
            }
        })
        .collect();
    done.sort_unstable_by_key(|&(t, _)| t);
    done.into_iter().map(|(_, r)| r).collect()
}

/// The tiles' results gathered: their pixels' sums written into `film` (if any), their
/// records listed in tile order, their counters summed.
fn gather(tiles: Vec<Tile>, mut film: Option<&mut Film>) -> BatchOutput {
    let mut out = BatchOutput {
        stats: RenderStats::default(),
        cut: false,
        records: Vec::with_capacity(tiles.len()),
        rrs_records: Vec::with_capacity(tiles.iter().map(|t| t.rrs_records.len()).sum()),
        total: DVec3::ZERO,
        tile_sums: Vec::new(),
    };
    for mut tile in tiles {
        if !tile.records.is_empty() {
            out.records.push(std::mem::take(&mut tile.records));
        }
        out.rrs_records.append(&mut tile.rrs_records);
        // the pixels a tile rendered, in its order (all of them unless it was cut short)
        let w = tile.size.x as usize;
        match film.as_deref_mut() {
            None => {
                out.total += tile.sums.iter().map(|s| s.0).sum::<DVec3>();
                out.tile_sums.push(TileSums {
                    origin: tile.origin,
                    width: tile.size.x,
                    sums: std::mem::take(&mut tile.sums),
                });
            }
            Some(film) => {
                for (k, &(s, s2, n)) in tile.sums.iter().enumerate() {
                    let (x, y) = (
                        tile.origin.x + (k % w) as u32,
                        tile.origin.y + (k / w) as u32,
                    );
                    film.set_pixel_sums(film.index(x, y), s, s2, n);
                }
            }
        }
        out.cut |= tile.cut;
        out.stats.rays.add(&tile.rays);
        out.stats.samples += tile.samples;
        out.stats.nonfinite += tile.nonfinite;
        out.stats.thread_time += tile.time;
    }
    out
}
