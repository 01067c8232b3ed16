//! What a render counts and how long it took ([`RenderStats`], [`GuideStats`]), and the text
//! `vrpt render` prints of them: the summary line, and with `--stats` the split of the thread
//! time between tracing and shading.

use super::*;
use crate::integrator::{PHASES, PHASE_NAMES, TIMED_PATH_EVERY};

/// Counts and times of one render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Wall time.
    pub elapsed: Duration,
    /// Rays traced, by kind.
    pub rays: RayCounts,
    /// Path samples taken (including dropped ones).
    pub samples: u64,
    /// Samples dropped because their radiance was NaN or infinite.
    pub nonfinite: u64,
    /// The pixels where samples spent edge rays (`--edge-rays`; [`super::edges`]).
    pub edge_pixels: u64,
    /// The edge rays (in `rays.edge`) that found those pixels: the edge map's probe and pilot,
    /// traced once whether or not it finds any (0 where the map was handed to the render).
    pub edge_finding: u64,
    /// Wall time summed over the tiles, i.e. over the worker threads (≈ `elapsed` × threads).
    pub thread_time: Duration,
    /// What path guiding's training did (guided directions only); `elapsed`, `rays` and
    /// `thread_time` include the training, `samples` does not.
    pub guide: Option<GuideStats>,
    /// What `--roulette ears`'s training did; `elapsed`, `rays` and `thread_time` include it,
    /// `samples` does not.
    pub rrs: Option<RrsStats>,
}

/// What the training of `--roulette ears` did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RrsStats {
    /// Training iterations rendered (of 2, 2, 4, 8 … spp; the first with classic roulette).
    pub iterations: u32,
    /// Their samples per pixel in all.
    pub training_spp: u64,
    /// Wall time of the training.
    pub training: Duration,
    /// Wall time of the image after it.
    pub final_time: Duration,
    /// The cache's nodes.
    pub nodes: usize,
    /// The image's factor `√(C_img / V_img)` (rays per sample over relative variance).
    pub image_factor: f32,
    /// The mean number of continuations at the camera ray's vertex in the last iteration.
    pub first_split: f64,
}

impl RrsStats {
    /// One line: the training's size and time, the cache, the image factor.
    pub fn summary(&self) -> String {
        format!(
            "ears: training {} spp in {} iterations, {:.3} s; image {:.3} s ({:.0}% of the time \
             training); cache {} nodes; image factor {:.3}; {:.2} continuations at the first vertex\n",
            self.training_spp,
            self.iterations,
            self.training.as_secs_f64(),
            self.final_time.as_secs_f64(),
            100.0 * self.training.as_secs_f64()
                / (self.training + self.final_time).as_secs_f64().max(1e-9),
            self.nodes,
            self.image_factor,
            self.first_split
        )
    }
}

/// What the training of a guided render did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GuideStats {
    /// Training iterations rendered (of 1, 2, 4, … spp).
    pub iterations: u32,
    /// Their samples per pixel in all.
    pub training_spp: u64,
    /// Wall time of the training (rendering and learning).
    pub training: Duration,
    /// Wall time of the final iteration (the image).
    pub final_time: Duration,
    /// The learned tree's size.
    pub tree: TreeSize,
    /// The training iterations kept in the image (`None`: the image is the final iteration
    /// alone).
    pub combined: Option<super::Combination>,
    /// The guide's gate, where the render gated ([`super::gate`]; with no reading where its
    /// training ended before the first probe).
    pub gate: Option<super::gate::Gate>,
}

impl GuideStats {
    /// One line: the time split and the tree's size.
    pub fn summary(&self) -> String {
        format!(
            "guiding: training {} spp in {} iterations, {:.3} s; final iteration {:.3} s \
             ({:.0}% of the time training); tree {} spatial leaves, {} quadtree nodes, {:.2} MiB\n",
            self.training_spp,
            self.iterations,
            self.training.as_secs_f64(),
            self.final_time.as_secs_f64(),
            100.0 * self.training.as_secs_f64()
                / (self.training + self.final_time).as_secs_f64().max(1e-9),
            self.tree.leaves,
            self.tree.quad_nodes,
            self.tree.bytes as f64 / (1024.0 * 1024.0)
        ) + &match self.combined {
            Some(c) => format!(
                "guiding: the image combines the final iteration with {} training images ({} \
                 iterations, {} of the gate's probes) by inverse variance (final iteration's \
                 weight {:.3})\n",
                c.iterations,
                c.iterations - c.probes,
                c.probes,
                c.final_weight
            ),
            None => String::new(),
        } + &self.gate.map_or(String::new(), |g| g.summary())
    }
}

impl RenderStats {
    /// Millions of rays per second of wall time.
    pub fn mrays_per_second(&self) -> f64 {
        self.rays.total() as f64 / self.elapsed.as_secs_f64().max(1e-9) / 1e6
    }

    /// Path samples per second of wall time.
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }

    /// What a render of `scene` with `settings` (its spp the spp reached) did, in three lines:
    /// the scene and its BVH, the speed, the rays by kind.
    /// Where the time went: loading (`load`, with the BVH build inside it) and, of the render's
    /// thread time, the share in BVH traversal and the rest (camera, sampler, surface and
    /// shading, light sampling, film), with the traversal's own ray rate per thread. The split
    /// needs [`RenderSettings::time_traces`]; without it only the totals are given.
    pub fn timing(&self, load: Duration, scene: &Scene) -> String {
        let thread = self.thread_time.as_secs_f64().max(1e-9);
        let (bvh, shading) = scene.memory_bytes();
        let n = scene.triangle_count().max(1) as f64;
        let mut s = format!(
            "memory: {:.1} MB of geometry, {:.0} bytes per triangle (BVH and triangles {:.0}, \
             shading data {:.0})\n",
            (bvh + shading) as f64 / 1e6,
            (bvh + shading) as f64 / n,
            bvh as f64 / n,
            shading as f64 / n
        );
        s += &format!(
            "time: scene load {:.1} ms (BVH build {:.1} ms), render {:.3} s = {:.3} thread-seconds",
            load.as_secs_f64() * 1e3,
            scene.accel.build_time.as_secs_f64() * 1e3,
            self.elapsed.as_secs_f64(),
            thread
        );
        if self.rays.timed > 0 {
            let trace = self.rays.trace_seconds();
            // (no rate where the timed rays took no measurable time: not "inf")
            let rate = if trace > 0.0 {
                format!(
                    " ({:.2} Mrays/s per thread while tracing)",
                    self.rays.total() as f64 / trace / 1e6
                )
            } else {
                String::new()
            };
            s += &format!(
                ": trace {:.1}%{rate}, shade and sample {:.1}%",
                100.0 * trace / thread,
                100.0 * (1.0 - trace / thread)
            );
        }
        s.push('\n');
        if let Some(line) = self.cost_per_sample() {
            s += &line;
        }
        if let Some(g) = &self.guide {
            s += &g.summary();
        }
        if let Some(r) = &self.rrs {
            s += &r.summary();
        }
        s
    }

    /// The cost model: nanoseconds of thread time per path sample in each phase of the paths
    /// timed phase by phase (one in [`TIMED_PATH_EVERY`]), and each phase per event where it
    /// has one (trace per closest-hit ray, shadow per shadow ray, shade per vertex). The clock's
    /// own cost is taken out twice over: as measured in an empty loop, then, where the phases
    /// still sum to more than the render's thread time per sample, the rest in proportion to
    /// each phase's clock reads (the clock costs more amid a path's work than in a loop of its
    /// own), so the phases sum to the thread time. `None` without timing.
    pub fn cost_per_sample(&self) -> Option<String> {
        let mut ns = self.rays.phase_ns_per_sample()?;
        let samples = self.samples.max(1) as f64;
        let per_thread = self.thread_time.as_secs_f64() * 1e9 / samples;
        // The clock costs more inside a path than in the empty loop that measured it: what the
        // phases sum to beyond the thread time per sample is that extra, taken from each phase
        // in proportion to its clock reads
        let reads: Vec<f64> = (0..PHASES)
            .map(|k| self.rays.phase_reads[k] as f64 / self.rays.paths_timed as f64)
            .collect();
        let excess = ns.iter().sum::<f64>() - per_thread;
        if excess > 0.0 {
            let per_read = excess / reads.iter().sum::<f64>().max(1.0);
            for k in 0..PHASES {
                ns[k] = (ns[k] - reads[k] * per_read).max(0.0);
            }
        }
        let closest = (self.rays.camera + self.rays.bounce) as f64 / samples;
        let shadow = self.rays.shadow as f64 / samples;
        let per = |k: usize, events: f64, what: &str| {
            if events > 0.0 {
                format!(" ({:.0} per {what})", ns[k] / events)
            } else {
                String::new()
            }
        };
        let parts: Vec<String> = (0..PHASES)
            .map(|k| {
                let extra = match k {
                    1 => per(k, closest, "ray"),
                    2 => per(k, closest, "hit"),
                    5 => per(k, shadow, "ray"),
                    _ => String::new(),
                };
                format!("{} {:.0}{extra}", PHASE_NAMES[k], ns[k])
            })
            .collect();
        Some(format!(
            "cost per sample, ns ({} paths timed, one in {TIMED_PATH_EVERY}; {:.0} thread-ns per \
             sample, of which the clock's extra cost {:.0} taken out): {}\n",
            self.rays.paths_timed,
            per_thread,
            excess.max(0.0),
            parts.join(", "),
        ))
    }

    /// The summary lines `vrpt render` prints: size, spp, strategy, time, rates and rays.
    pub fn summary(&self, scene: &Scene, settings: &RenderSettings) -> String {
        let textures = match scene.textures.textures.len() {
            0 => String::new(),
            n => format!(
                ", {n} textures ({:.1} KiB)",
                scene.textures.bytes() as f64 / 1024.0
            ),
        };
        let reuse = match settings.reuse {
            1 => String::new(),
            k => format!(", reuse {k}×{k}"),
        };
        let connections = match self.rays.connection {
            0 => String::new(),
            n => format!(", {n} of them reuse connections"),
        };
        let edges = match (self.rays.edge, self.edge_pixels) {
            (0, _) => String::new(),
            (n, 0) => format!(", {n} of them edge rays looking for edge pixels (none found)"),
            (n, k) => match self.edge_finding {
                0 => format!(", {n} of them edge rays in {k} edge pixels"),
                f => format!(
                    ", {n} of them edge rays in {k} edge pixels ({f} of them finding those)"
                ),
            },
        };
        // the light through a mirror or glass after a Phong vertex, where there was any
        let caustic = match self.rays.caustic > 0.0 {
            true => format!(
                "; {:.1}% of the light caustic",
                100.0 * self.rays.caustic_share()
            ),
            false => String::new(),
        };
        // the light found from the second vertex on (what path reuse shares)
        let indirect = match self.rays.light > 0.0 {
            true => format!(
                "; {:.1}% of the light indirect",
                100.0 * self.rays.indirect_share()
            ),
            false => String::new(),
        };
        format!(
            "{}: {} triangles, BVH built in {:.1} ms ({:.1} KiB){textures}\n\
             rendered {}x{} at {} spp ({}{reuse}, max depth {}) in {:.3} s: {:.3} M samples/s, {:.2} Mrays/s\n\
             rays: {} ({} camera{edges}, {} bounce, {} shadow{connections}; {:.2} per sample{caustic}{indirect})\n",
            scene.source.display(),
            scene.triangle_count(),
            scene.accel.build_time.as_secs_f64() * 1e3,
            scene.accel.memory_bytes() as f64 / 1024.0,
            settings.width,
            settings.height,
            settings.spp,
            settings.strategy.axes_name(),
            settings.max_depth,
            self.elapsed.as_secs_f64(),
            self.samples_per_second() / 1e6,
            self.mrays_per_second(),
            self.rays.total(),
            self.rays.camera,
            self.rays.bounce,
            self.rays.shadow,
            self.rays.total() as f64 / self.samples.max(1) as f64
        )
    }
}
