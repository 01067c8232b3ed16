//! The tile kernel with path reuse ([`crate::integrator::reuse`]): a tile's pixels trace one
//! sample each, side by side, then each pixel's estimate combines the paths of its `k × k`
//! block, on a grid shifted by a hash of the seed, the tile and the sample.

use super::*;
use crate::integrator::reuse::{combine, Split, MAX_BLOCK};
use crate::math::hash_words;

impl<F: SamplerFactory> Kernel<'_, F> {
    /// Tile `t` of `batch` with path reuse in blocks of `k × k` pixels
    /// ([`crate::integrator::reuse`]): sample by sample, every pixel of the tile traces its
    /// path (with its own sampler of `samplers`, one per pixel of a tile), then each pixel's
    /// estimate combines the paths of its block. The blocks' grid is shifted by a hash of the
    /// seed and the sample (blocks end at the tile's edges), so a block's shared error falls
    /// on other neighbours in every sample rather than printing the grid into the image; the
    /// partition is fixed before the paths are drawn, so each sample stays unbiased. In an
    /// adaptive round a pixel takes part in the tile's first `count` samples, its own. The
    /// stop flag is read before every sample of the tile; a tile it cuts keeps its sums from
    /// before. Every pixel's sums are returned, in row order.
    pub(super) fn tile_reused(
        &self,
        t: u32,
        k: u32,
        batch: &Batch,
        sums: Option<&Film>,
        samplers: &mut [F::Sampler],
    ) -> Tile {
        let tile_start = Instant::now();
        let mut tile = self.empty_tile(t);
        let (origin, size) = (tile.origin, tile.size);
        let n = (size.x * size.y) as usize;
        let (first, count) = self.reused_sets(&mut tile, batch, sums, samplers);
        // per pixel of the tile: what it adds
        let mut added = vec![(DVec3::ZERO, DVec3::ZERO, 0u64); n];
        let mut splits = vec![Split::new(); n];
        let mut seen = vec![Vec3::ZERO; n];
        let (mut nonfinite, mut samples) = (0u64, 0u64);
        let image_t = self.strip.map_or(t, |s| s.image_tile(t));
        let steps = count.iter().copied().max().unwrap_or(0);
        for step in 0..steps {
            if batch.stop.is_some_and(|f| f.load(Ordering::Relaxed)) {
                tile.cut = true;
                break;
            }
            for q in 0..n {
                splits[q] = Split::new();
                if step >= count[q] {
                    continue; // its own samples are done: no part in this one
                }
                let pixel = UVec2::new(origin.x + q as u32 % size.x, origin.y + q as u32 / size.x);
                let sampler = &mut samplers[q];
                let (integrator, m, image) = self.edge_rays(pixel);
                let ray = self.camera_ray(pixel, first[q] + step, sampler, &mut tile.rays);
                radiance_split(
                    self.scene,
                    ray,
                    sampler,
                    integrator,
                    &mut tile.rays,
                    &mut tile.stack,
                    self.guide.tree,
                    &mut splits[q],
                );
                let (rays, stack) = (&mut tile.rays, &mut tile.stack);
                seen[q] = self.seen(image, first[q] + step, m, rays, stack);
                tile.rays.end_path();
            }
            let index = first[0] + step;
            let live = |q: usize| step < count[q];
            let paths = (&splits[..], &seen[..]);
            let (n_new, bad) =
                self.combine_blocks((image_t, k, index), paths, live, &mut tile, &mut added);
            (samples, nonfinite) = (samples + n_new, nonfinite + bad);
        }
        if !tile.cut {
            for (s, a) in tile.sums.iter_mut().zip(&added) {
                (s.0, s.1, s.2) = (s.0 + a.0, s.1 + a.1, s.2 + a.2);
            }
            tile.samples = samples;
            tile.nonfinite = nonfinite;
        }
        self.progress.advance(tile.samples);
        tile.time = tile_start.elapsed();
        tile
    }

    /// One sample of a reusing tile after its paths `splits` (one per pixel of `tile`, row
    /// order) and what its edge rays saw (`seen`, likewise): the tile cut into `k × k` blocks on
    /// a grid shifted by a hash of the seed, the tile `t` and the sample `index`, each block's
    /// estimates combined and added to `added` for the pixels `live` says take part. The
    /// samples added and the non-finite ones.
    fn combine_blocks(
        &self,
        (t, k, index): (u32, u32, u64),
        (splits, seen): (&[Split], &[Vec3]),
        live: impl Fn(usize) -> bool,
        tile: &mut Tile,
        added: &mut [Sums],
    ) -> (u64, u64) {
        let size = tile.size;
        let mut block = [Split::new(); MAX_BLOCK];
        let mut at = [0usize; MAX_BLOCK];
        let mut out = [Vec3::ZERO; MAX_BLOCK];
        let (mut samples, mut nonfinite) = (0, 0);
        // the grid's shift in this sample (the same for every pixel but in adaptive rounds)
        let h = hash_words(&[self.seed ^ 0x5245_5553_4520_4b21, t as u64, index]);
        let (sx, sy) = ((h % k as u64) as u32, ((h >> 32) % k as u64) as u32);
        let edges = |size: u32, shift: u32| {
            let mut e = 0;
            std::iter::from_fn(move || {
                (e < size).then(|| {
                    let end = if e == 0 && shift > 0 { shift } else { e + k }.min(size);
                    let r = e..end;
                    e = end;
                    r
                })
            })
        };
        for ys in edges(size.y, sy) {
            for xs in edges(size.x, sx) {
                let mut m = 0;
                for y in ys.clone() {
                    for x in xs.clone() {
                        let q = (y * size.x + x) as usize;
                        (block[m], at[m]) = (splits[q], q);
                        m += 1;
                    }
                }
                combine(
                    self.scene,
                    self.integrator.directions,
                    &block[..m],
                    &mut tile.rays,
                    &mut tile.stack,
                    &mut out[..m],
                );
                for (&q, l) in at[..m].iter().zip(&out[..m]).filter(|(&q, _)| live(q)) {
                    samples += 1;
                    let l = *l + seen[q];
                    if l.is_finite() {
                        let v = l.as_dvec3();
                        added[q].0 += v;
                        added[q].1 += v * v;
                        added[q].2 += 1;
                    } else {
                        nonfinite += 1;
                    }
                }
            }
        }
        (samples, nonfinite)
    }

    /// The sample sets of a reusing tile's pixels (row order): each one's first sample index
    /// and count (a pass's range, or in an adaptive round the pixel's own set, its sampler in
    /// `samplers` made for it), and the pixel's sums from `sums` (if any) pushed to `tile`.
    fn reused_sets(
        &self,
        tile: &mut Tile,
        batch: &Batch,
        sums: Option<&Film>,
        samplers: &mut [F::Sampler],
    ) -> (Vec<u64>, Vec<u64>) {
        let (origin, size) = (tile.origin, tile.size);
        let n = (size.x * size.y) as usize;
        let (mut first, mut count) = (vec![0u64; n], vec![0u64; n]);
        for q in 0..n {
            let (x, y) = (origin.x + q as u32 % size.x, origin.y + q as u32 / size.x);
            let i = (y * self.width + x) as usize;
            tile.sums
                .push(sums.map_or((DVec3::ZERO, DVec3::ZERO, 0), |f| f.pixel_sums(i)));
            (first[q], count[q]) = match &batch.samples {
                Samples::Pass { range, .. } => (range.start, range.end - range.start),
                Samples::Own(a) => {
                    let set = SamplePass {
                        origin: a.origin[i] as u32,
                        size: a.count[i],
                    };
                    samplers[q] = self.factory.make(self.seed, set);
                    (a.origin[i], a.count[i] as u64)
                }
            };
        }
        (first, count)
    }
}
