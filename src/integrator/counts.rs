//! What a render counts of its rays, of the light its paths carried (all of it, the part that
//! came through a delta vertex after a Phong one: [`RayCounts::caustic_share`], and the part
//! found from the second vertex on: [`RayCounts::indirect_share`]) and, under
//! `--stats`, of its time: [`RayCounts`] by kind, one traversal in [`TIMED_RAY_EVERY`] timed, and one path sample in [`TIMED_PATH_EVERY`]
//! timed phase by phase ([`Phase`]), the clock's own cost measured by [`clock_overhead_ns`].

/// The parts a path sample's cost is split into when it is timed phase by phase
/// ([`RayCounts::start_path`]): each clock read ends the phase it names, so the phases tile the
/// sample's time with no gap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The sampler's start of the pixel sample, the pixel point and the camera ray.
    Camera,
    /// Closest-hit traversals (camera and bounce rays), and the environment where one misses.
    Trace,
    /// The surface point, its emission (with its MIS weight), material, BSDF and shading frame.
    Shade,
    /// The bounce's sample values.
    Sampler,
    /// A light sample's choice of light and its point on it.
    Light,
    /// Shadow rays.
    Shadow,
    /// BSDF evaluation and pdf for the light sample, and the bounce's direction.
    Bsdf,
    /// The sample added to its pixel's sums.
    Film,
}

/// How many [`Phase`]s there are.
pub const PHASES: usize = 8;

/// The phases' names in `--stats`, in [`Phase`] order.
pub const PHASE_NAMES: [&str; PHASES] = [
    "camera", "trace", "shade", "sampler", "light", "shadow", "bsdf", "film",
];

/// With timing on, one path sample in this many is timed phase by phase (about 30 clock reads
/// of ~20 ns each on a Cornell-box path of ~1 µs: one in 61 costs ~1 %). Counted over a tile's
/// paths, and a prime, so that the timed ones fall on every sample index of a pixel alike: the
/// first sample of a pixel's pass builds the stratified sampler's tables, and timing only those
/// read the sampler at 1.7 µs a sample.
pub const TIMED_PATH_EVERY: u64 = 61;

/// Rays traced, by kind, and the light the paths carried.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCounts {
    pub camera: u64,
    /// Rays continuing a path after a bounce.
    pub bounce: u64,
    /// Occlusion rays toward light samples, and those of path reuse's connections.
    pub shadow: u64,
    /// Path reuse's connections (their shadow rays, also counted in `shadow`).
    pub connection: u64,
    /// Camera rays that look only for the emission seen directly (`--edge-rays`; also counted
    /// in `camera`).
    pub edge: u64,
    /// The luminance of every path estimate the path tracer returned, summed (a reused path's
    /// continuation counted as traced). Each tile counts its own, and a render sums its tiles
    /// in their order, so the sum is the same on any number of threads. Not counted by
    /// `--roulette ears`'s branching paths.
    pub light: f64,
    /// The part of [`RayCounts::light`] a path found as emission through a delta vertex (a
    /// mirror or glass) after a Phong vertex: a caustic, light no light sample can reach and only
    /// a bounce from the Phong vertex before it finds, which is what a guide learns to aim.
    pub caustic: f64,
    /// The part of [`RayCounts::light`] a path found from its second vertex on: the second
    /// vertex's light sample and everything after its bounce (not the emission the first
    /// bounce hit there, which is the first vertex's direct light under MIS). It is the light
    /// path reuse shares between pixels ([`super::reuse`]: a reused tail is a second vertex);
    /// a reusing path counts its tail's part of the light alone.
    pub indirect: f64,
    /// Nanoseconds spent in the timed traversals, when [`super::IntegratorSettings::time_traces`]
    /// is on.
    pub trace_ns: u64,
    /// How many traversals were timed.
    pub timed: u64,
    /// Nanoseconds of each [`Phase`] in the path samples timed phase by phase.
    pub phase_ns: [u64; PHASES],
    /// Clock reads that ended each phase (each carries the clock's own cost).
    pub phase_reads: [u64; PHASES],
    /// Path samples timed phase by phase.
    pub paths_timed: u64,
    /// Path samples started (the count [`RayCounts::start_path`] picks by).
    paths_started: u64,
    /// The clock at the last phase's end, while a path is timed.
    lap: Option<std::time::Instant>,
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.camera + self.bounce + self.shadow
    }

    /// The share of the light the paths carried that was caustic ([`RayCounts::caustic`]); 0
    /// where they carried none.
    pub fn caustic_share(&self) -> f64 {
        match self.light > 0.0 {
            true => (self.caustic / self.light).clamp(0.0, 1.0),
            false => 0.0,
        }
    }

    /// The share of the light the paths carried that was indirect ([`RayCounts::indirect`]); 0
    /// where they carried none.
    pub fn indirect_share(&self) -> f64 {
        match self.light > 0.0 {
            true => (self.indirect / self.light).clamp(0.0, 1.0),
            false => 0.0,
        }
    }

    /// Add `o`'s counts.
    pub fn add(&mut self, o: &RayCounts) {
        self.camera += o.camera;
        self.bounce += o.bounce;
        self.shadow += o.shadow;
        self.connection += o.connection;
        self.edge += o.edge;
        self.light += o.light;
        self.caustic += o.caustic;
        self.indirect += o.indirect;
        self.trace_ns += o.trace_ns;
        self.timed += o.timed;
        for k in 0..PHASES {
            self.phase_ns[k] += o.phase_ns[k];
            self.phase_reads[k] += o.phase_reads[k];
        }
        self.paths_timed += o.paths_timed;
        self.paths_started += o.paths_started;
    }

    /// A path sample starts: timed phase by phase when `on` and it is a [`TIMED_PATH_EVERY`]-th
    /// one; [`RayCounts::mark`] then ends each phase and [`RayCounts::end_path`] the path.
    #[inline(always)]
    pub fn start_path(&mut self, on: bool) {
        self.paths_started += 1;
        if on && self.paths_started.is_multiple_of(TIMED_PATH_EVERY) {
            self.lap = Some(std::time::Instant::now());
            self.paths_timed += 1;
        }
    }

    /// End `phase` of a timed path (nothing on a path not timed): the time since the last
    /// phase ended goes to it, capped at 10 µs (longer is the thread descheduled).
    #[inline(always)]
    pub fn mark(&mut self, phase: Phase) {
        if let Some(last) = self.lap {
            let now = std::time::Instant::now();
            let k = phase as usize;
            self.phase_ns[k] += ((now - last).as_nanos() as u64).min(MAX_TRACE_NS);
            self.phase_reads[k] += 1;
            self.lap = Some(now);
        }
    }

    /// End a timed path with its [`Phase::Film`].
    #[inline(always)]
    pub fn end_path(&mut self) {
        self.mark(Phase::Film);
        self.lap = None;
    }

    /// Nanoseconds per path sample in each [`Phase`], from the paths timed phase by phase, the
    /// clock's own cost ([`clock_overhead_ns`], one read per phase end) subtracted; `None`
    /// when no path was timed.
    pub fn phase_ns_per_sample(&self) -> Option<[f64; PHASES]> {
        if self.paths_timed == 0 {
            return None;
        }
        let read = clock_overhead_ns();
        Some(std::array::from_fn(|k| {
            (self.phase_ns[k] as f64 - self.phase_reads[k] as f64 * read).max(0.0)
                / self.paths_timed as f64
        }))
    }

    /// Estimated time in BVH traversal: the timed rays' time, less the clock's own cost inside
    /// each interval ([`clock_overhead_ns`]), scaled to all rays (the timed ones are every
    /// [`TIMED_RAY_EVERY`]-th ray by count, of every kind).
    pub fn trace_seconds(&self) -> f64 {
        if self.timed == 0 {
            return 0.0;
        }
        let ns = (self.trace_ns as f64 - self.timed as f64 * clock_overhead_ns()).max(0.0);
        ns * 1e-9 * self.total() as f64 / self.timed as f64
    }
}

/// With timing on, one ray in this many is timed: two clock reads (~40 ns here) on every ray
/// would add a fifth to the render and inflate the traced share; one in 16 costs ~1%.
pub const TIMED_RAY_EVERY: u64 = 16;

/// The most one timed traversal counts, in nanoseconds: 16× the slowest ray measured (0.63 µs
/// per incoherent ray through 4 million triangles); longer intervals are preemption.
const MAX_TRACE_NS: u64 = 10_000;

/// What an empty interval of `timed` measures (the clock read's own cost), in nanoseconds:
/// the median of 101 batch means of 100 empty intervals each, measured once per process. A
/// median, not the mean of all: one preemption inside the loop (milliseconds, on a shared
/// machine) made a mean of 10,000 intervals read hundreds of ns, and every phase of `--stats`
/// then read 0 once the overhead was taken out.
pub fn clock_overhead_ns() -> f64 {
    static OVERHEAD: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *OVERHEAD.get_or_init(|| {
        median_batch_mean(|| {
            let start = std::time::Instant::now();
            std::hint::black_box(start).elapsed().as_nanos()
        })
    })
}

/// The median of 101 means of 100 values of `interval()` each: the mean of a typical batch,
/// which a few outliers (preemptions) cannot move.
fn median_batch_mean(mut interval: impl FnMut() -> u128) -> f64 {
    let mut means: Vec<f64> = (0..101)
        .map(|_| (0..100).map(|_| interval()).sum::<u128>() as f64 / 100.0)
        .collect();
    means.sort_by(f64::total_cmp);
    means[means.len() / 2]
}

/// `f()` (a traversal, already counted in `rays`), timed when `on` and it is the
/// [`TIMED_RAY_EVERY`]-th ray.
#[inline(always)]
pub(super) fn timed<T>(on: bool, rays: &mut RayCounts, f: impl FnOnce() -> T) -> T {
    // not inside a path timed phase by phase: its clock reads would land in the phase
    if on && rays.total().is_multiple_of(TIMED_RAY_EVERY) && rays.lap.is_none() {
        let start = std::time::Instant::now();
        let r = f();
        // an interval longer than any traversal is the thread being descheduled: scaled by
        // TIMED_RAY_EVERY it would swamp the estimate, so it counts as MAX_TRACE_NS
        rays.trace_ns += (start.elapsed().as_nanos() as u64).min(MAX_TRACE_NS);
        rays.timed += 1;
        r
    } else {
        f()
    }
}

#[cfg(test)]
mod tests {
    use super::median_batch_mean;

    /// The clock's cost survives preemptions: intervals of 20 ns with three of 5 ms among the
    /// 10,100 (the thread descheduled) still read 20 ns; the plain mean read 20 + 3·5·10⁶/10,100
    /// ≈ 1505 ns, which made every phase of `--stats` 0. Intervals alternating 10 and 30 ns read
    /// their mean, 20.
    #[test]
    fn clock_overhead_ignores_preemptions() {
        let mut i = 0u64;
        let spiky = median_batch_mean(|| {
            i += 1;
            if [17, 4_000, 9_999].contains(&i) {
                5_000_000
            } else {
                20
            }
        });
        assert_eq!(spiky, 20.0);
        let mut j = 0u64;
        let alternating = median_batch_mean(|| {
            j += 1;
            if j.is_multiple_of(2) {
                10
            } else {
                30
            }
        });
        assert_eq!(alternating, 20.0);
    }
}
