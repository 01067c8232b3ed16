//! The tile kernel: rayon over 16×16 tiles; per pixel its samples, in index order, through the
//! integrator into the pixel's sums (a pass's range, or in an adaptive round the pixel's own
//! set), with the stop flag read between pixels and every 256 samples of one.

use super::*;

/// One tile's result: pixel sums and counters.
struct TileResult {
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

/// Render the samples `range` (sample indices, all within `pass` and below
/// [`SAMPLE_INDICES`]) of the tiles `tiles` (row-major tile indices) into `film`, going on from
/// the sums it holds, on the current rayon pool, with the sampler `factory` makes for the pass
/// and `settings.seed`; with `alloc`, each pixel's own set instead of `pass` and `range`.
/// With `stop`, a tile reads the flag before each pixel (and every 256 samples of one) and ends
/// there when it is set: the second value says whether some pixel was left out (the film then
/// holds a partial batch, for the caller to drop).
#[allow(clippy::too_many_arguments)]
pub(super) fn render_with<F: SamplerFactory>(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    factory: &F,
    (pass, range, tiles, stop, alloc): (
        SamplePass,
        Range<u64>,
        Range<u32>,
        Option<&AtomicBool>,
        Option<Alloc>,
    ),
    guide: Guide,
    mut film: Option<&mut Film>,
    progress: &dyn Progress,
) -> (RenderStats, bool, Vec<Record>, DVec3) {
    let start = Instant::now();
    // training renders keep no film: their samples only teach the guide
    let sums = film.as_deref();
    let integrator = settings.integrator();
    let sampler = factory.make(settings.seed, pass);
    let tiles_x = settings.width.div_ceil(TILE);
    let tiles: Vec<TileResult> = tiles
        .into_par_iter()
        .map_with(sampler, |sampler, t| {
            let tile_start = Instant::now();
            let origin = UVec2::new((t % tiles_x) * TILE, (t / tiles_x) * TILE);
            let size = UVec2::new(
                TILE.min(settings.width - origin.x),
                TILE.min(settings.height - origin.y),
            );
            let mut tile = TileResult {
                origin,
                size,
                sums: Vec::with_capacity((size.x * size.y) as usize),
                rays: RayCounts::default(),
                samples: 0,
                nonfinite: 0,
                time: Duration::ZERO,
                cut: false,
                records: Vec::new(),
            };
            let mut stack = TraceStack::default();
            'pixels: for y in origin.y..origin.y + size.y {
                for x in origin.x..origin.x + size.x {
                    if stop.is_some_and(|f| f.load(Ordering::Relaxed)) {
                        tile.cut = true;
                        break 'pixels;
                    }
                    let pixel = UVec2::new(x, y);
                    let i = (y * settings.width + x) as usize;
                    let (mut sum, mut sum_sq, mut n) =
                        sums.map_or((DVec3::ZERO, DVec3::ZERO, 0), |f| f.pixel_sums(i));
                    let range = match alloc {
                        None => range.clone(),
                        Some(a) => {
                            let set = SamplePass {
                                origin: a.origin[i] as u32,
                                size: a.count[i],
                            };
                            *sampler = factory.make(settings.seed, set);
                            a.origin[i]..a.origin[i] + a.count[i] as u64
                        }
                    };
                    for index in range.clone() {
                        // a long pixel reads the flag too (every 256 samples: a relaxed load)
                        if index % 256 == 255 && stop.is_some_and(|f| f.load(Ordering::Relaxed)) {
                            tile.cut = true;
                            break 'pixels;
                        }
                        // below SAMPLE_INDICES (checked by camera_for): a u32
                        sampler.start_pixel_sample(pixel, index as u32);
                        let ray = camera.generate_ray(pixel, CameraSample::draw(sampler).pixel);
                        let l = radiance_guided(
                            scene,
                            ray,
                            sampler,
                            &integrator,
                            &mut tile.rays,
                            &mut stack,
                            guide.tree,
                            guide.record.then_some(&mut tile.records),
                        );
                        if l.is_finite() {
                            let v = l.as_dvec3();
                            sum += v;
                            sum_sq += v * v;
                            n += 1;
                        } else {
                            tile.nonfinite += 1;
                        }
                    }
                    tile.samples += range.end - range.start;
                    tile.sums.push((sum, sum_sq, n));
                }
            }
            progress.advance(tile.samples);
            tile.time = tile_start.elapsed();
            tile
        })
        .collect();
    let mut stats = RenderStats::default();
    let mut cut = false;
    let mut records = Vec::with_capacity(tiles.iter().map(|t| t.records.len()).sum());
    // what the samples added (the pixels' sums less what the film held before)
    let mut total = DVec3::ZERO;
    for mut tile in tiles {
        records.append(&mut tile.records);
        if film.is_none() {
            total += tile.sums.iter().map(|s| s.0).sum::<DVec3>();
        }
        // the pixels a tile rendered, in its order (all of them unless it was cut short)
        let w = tile.size.x as usize;
        if let Some(film) = film.as_deref_mut() {
            for (k, &(s, s2, n)) in tile.sums.iter().enumerate() {
                let (x, y) = (
                    tile.origin.x + (k % w) as u32,
                    tile.origin.y + (k / w) as u32,
                );
                film.set_pixel_sums(film.index(x, y), s, s2, n);
            }
        }
        cut |= tile.cut;
        stats.rays.add(&tile.rays);
        stats.samples += tile.samples;
        stats.nonfinite += tile.nonfinite;
        stats.thread_time += tile.time;
    }
    stats.elapsed = start.elapsed();
    (stats, cut, records, total)
}
