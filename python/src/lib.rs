//! `vrpt._native`: the Python binding's native half, a thin layer over the vrpt library.
//!
//! Every command comes in as its command-line flags (`["--spp", "64", …]`, built from keyword
//! arguments by `vrpt/__init__.py`), parsed by [`vrpt::commands::parse_flags`] into the same
//! request the binary builds, and run by the same library function: the defaults, the checks and
//! the messages are the CLI's. Out come plain data: images as bytes of native-endian `f32`
//! (`numpy.frombuffer` makes them arrays without a copy), tables as JSON text of the library's
//! own serialized rows. No rendering logic lives here.
//!
//! The GIL is released while vrpt works. A render runs on a thread of its own while the calling
//! thread waits in slices of [`SIGNAL_POLL`], taking the GIL back only to let Python's signal
//! handlers run: Ctrl-C sets the render's stop flag, and the render returns the image of the
//! samples taken, as `vrpt render` does.
//!
//! A sampler written in Python is a callable `sampler(pixel=(x, y), first=i0, n=n, dims=d,
//! seed=s)` returning the `n × d` numbers of a pixel's set of samples `i0 .. i0 + n` as bytes of
//! `f32` (the Python half checks and converts what the user's function returns). It plugs into
//! [`vrpt::render::SamplerFactory`], the entry every sampler of the library goes through.

use glam::{UVec2, Vec2, Vec3};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::Duration;
use vrpt::analysis::experiments::Entry;
use vrpt::commands::experiment::{self, Experiment};
use vrpt::commands::{self, render::RenderRequest};
use vrpt::image_io::RgbImage;
use vrpt::render::{NoProgress, SamplePass};
use vrpt::sampler::{layout, Sampler, ONE_MINUS_EPSILON};
use vrpt::strategy::Strategy;

/// How often a waiting call lets Python's signal handlers run (Ctrl-C).
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// A library error as the Python exception of its kind, with the CLI's one-line message.
fn py_err(e: vrpt::Error) -> PyErr {
    let message = e.to_string();
    match e {
        vrpt::Error::NotFound { .. } => PyFileNotFoundError::new_err(message),
        vrpt::Error::Read { .. } | vrpt::Error::Write { .. } | vrpt::Error::ImageRead { .. } => {
            PyOSError::new_err(message)
        }
        _ => PyValueError::new_err(message),
    }
}

/// `work` on a thread of its own with the GIL released; meanwhile Python's signal handlers run
/// every [`SIGNAL_POLL`], and the first interrupt (an error from them, KeyboardInterrupt) sets
/// `stop`. The work's result, and whether it was interrupted.
fn interruptible<T: Send>(
    py: Python<'_>,
    stop: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> (T, bool) {
    py.detach(|| {
        std::thread::scope(|s| {
            let (tx, rx) = mpsc::channel();
            s.spawn(move || tx.send(work()));
            let mut interrupted = false;
            loop {
                match rx.recv_timeout(SIGNAL_POLL) {
                    Ok(result) => return (result, interrupted),
                    Err(mpsc::RecvTimeoutError::Timeout) => {
                        if !interrupted && Python::attach(|py| py.check_signals()).is_err() {
                            stop.store(true, Ordering::SeqCst);
                            interrupted = true;
                        }
                    }
                    Err(mpsc::RecvTimeoutError::Disconnected) => {
                        panic!("the render's thread ended without a result")
                    }
                }
            }
        })
    })
}

/// `f32`s as native-endian bytes.
fn f32_bytes(values: impl Iterator<Item = f32>) -> Vec<u8> {
    values.flat_map(f32::to_ne_bytes).collect()
}

/// RGB pixels as bytes of `f32`, row-major, 3 per pixel.
fn rgb_bytes(pixels: &[Vec3]) -> Vec<u8> {
    f32_bytes(pixels.iter().flat_map(|p| p.to_array()))
}

/// An image as vrpt writes it to an EXR: mean, variance of the mean, samples per pixel, the
/// replicates' estimated variance, metadata; for a render, also what the render said, and the
/// film to write it from.
#[pyclass(module = "vrpt._native", frozen)]
struct NativeImage {
    image: RgbImage,
    render: Option<commands::render::RenderOutcome>,
}

#[pymethods]
impl NativeImage {
    #[getter]
    fn width(&self) -> u32 {
        self.image.width
    }
    #[getter]
    fn height(&self) -> u32 {
        self.image.height
    }
    /// The mean, `height × width × 3` `f32` as bytes.
    fn pixels<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &rgb_bytes(&self.image.pixels))
    }
    /// The variance of each pixel's mean (from its samples), or `None`.
    fn variance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyBytes>> {
        (self.image.variance.as_deref()).map(|v| PyBytes::new(py, &rgb_bytes(v)))
    }
    /// The estimated variance of each pixel's mean from the replicates, or `None`.
    fn estimated_variance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyBytes>> {
        (self.image.estimated_variance.as_deref()).map(|v| PyBytes::new(py, &rgb_bytes(v)))
    }
    /// Samples in each pixel's mean, `u32` as bytes, or `None`.
    fn samples<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyBytes>> {
        let s = self.image.samples.as_deref()?;
        let bytes: Vec<u8> = s.iter().flat_map(|c| c.to_ne_bytes()).collect();
        Some(PyBytes::new(py, &bytes))
    }
    /// The metadata, keys without the EXR's `vrpt.` prefix, values as written.
    fn metadata<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in &self.image.metadata {
            d.set_item(k, v)?;
        }
        Ok(d)
    }
    /// What the render printed (scene, speed, rays, error), or `""` for an image read.
    #[getter]
    fn summary(&self) -> String {
        self.render
            .as_ref()
            .map_or(String::new(), |r| r.summary.clone())
    }
    /// Where the render's time went, or `""`.
    #[getter]
    fn timing(&self) -> String {
        self.render
            .as_ref()
            .map_or(String::new(), |r| r.timing.clone())
    }
    /// What the render warned of (dropped samples, a black image, an interrupt).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.render.as_ref().map_or(Vec::new(), |r| r.warnings())
    }
    /// Whether an interrupt ended the render before all its samples.
    #[getter]
    fn interrupted(&self) -> bool {
        self.render.as_ref().is_some_and(|r| r.interrupted)
    }
    /// Write a render as `vrpt render -o PATH` would (EXR with metadata, or PNG).
    #[pyo3(signature = (path, exposure = 0.0, variance = None))]
    fn save(&self, path: PathBuf, exposure: f32, variance: Option<PathBuf>) -> PyResult<()> {
        match &self.render {
            Some(r) => r
                .write(&path, exposure, variance.as_deref())
                .map_err(py_err),
            None => Err(PyValueError::new_err(
                "only a render is saved; an image read from a file is already one",
            )),
        }
    }
}

impl NativeImage {
    /// The image of a render, as its EXR holds it.
    fn of_render(r: commands::render::RenderOutcome) -> NativeImage {
        let image = RgbImage {
            estimated_variance: (r.estimate.method != vrpt::estimate::Method::Undefined)
                .then(|| r.estimate.variance.clone()),
            ..vrpt::output::render_image(&r.film, &r.meta)
        };
        NativeImage {
            image,
            render: Some(r),
        }
    }
}

/// What a sampler written in Python shares across the worker threads: the callable, the
/// numbers a path sample may draw, and the first error (after which every draw is 0.5 and the
/// render is stopped).
struct PySamplerShared {
    call: Py<PyAny>,
    dims: usize,
    failed: Mutex<Option<PyErr>>,
    stop: Arc<AtomicBool>,
}

/// A sampler written in Python: it asks the callable for a pixel's whole set of the pass at
/// the pixel's first sample, and serves its rows.
#[derive(Clone)]
struct PySampler {
    shared: Arc<PySamplerShared>,
    seed: u64,
    pass: SamplePass,
    pixel: Option<UVec2>,
    /// The pixel's set, `pass.size × dims`.
    values: Vec<f32>,
    /// The current sample's first number in `values`, and the numbers it has drawn.
    row: usize,
    dim: usize,
}

impl PySampler {
    /// Ask the callable for the set of `pixel`; on an error keep the first, stop the render,
    /// and fill with 0.5.
    fn fetch(&mut self, pixel: UVec2) {
        let (n, dims) = (self.pass.size as usize, self.shared.dims);
        let got = Python::attach(|py| -> PyResult<Vec<f32>> {
            let kwargs = PyDict::new(py);
            kwargs.set_item("pixel", (pixel.x, pixel.y))?;
            kwargs.set_item("first", self.pass.origin)?;
            kwargs.set_item("n", n)?;
            kwargs.set_item("dims", dims)?;
            kwargs.set_item("seed", self.seed)?;
            let out = self.shared.call.call(py, (), Some(&kwargs))?;
            let bytes = out.bind(py).cast::<PyBytes>()?.as_bytes();
            if bytes.len() != n * dims * 4 {
                return Err(PyValueError::new_err(format!(
                    "the sampler gave {} bytes, not the {n} × {dims} float32 asked for",
                    bytes.len()
                )));
            }
            Ok(bytes
                .chunks_exact(4)
                .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
                .collect())
        });
        self.values = got.unwrap_or_else(|e| {
            self.fail(e);
            vec![0.5; n * dims]
        });
        self.pixel = Some(pixel);
    }

    fn fail(&self, e: PyErr) {
        let mut first = self.shared.failed.lock().unwrap_or_else(|p| p.into_inner());
        first.get_or_insert(e);
        self.shared.stop.store(true, Ordering::SeqCst);
    }
}

impl Sampler for PySampler {
    fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
        if self.pixel != Some(pixel) {
            self.fetch(pixel);
        }
        self.row = index.saturating_sub(self.pass.origin) as usize * self.shared.dims;
        self.dim = 0;
    }

    fn next_1d(&mut self) -> f32 {
        let v = if self.dim < self.shared.dims {
            self.values.get(self.row + self.dim).copied().unwrap_or(0.5)
        } else {
            let asked = self.shared.dims;
            self.fail(PyValueError::new_err(format!(
                "a path drew more than the {asked} numbers vrpt asked the sampler for"
            )));
            0.5
        };
        self.dim += 1;
        v.clamp(0.0, ONE_MINUS_EPSILON)
    }

    fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_1d(), self.next_1d())
    }
}

/// The most numbers one path sample draws under `strategy` with paths of `max_depth` segments:
/// the camera's, and a bounce's at every vertex ([`layout`]).
fn numbers_per_sample(strategy: &Strategy, max_depth: u32) -> usize {
    let count = |dims: &[layout::Dim]| -> usize {
        dims.iter()
            .map(|d| match d {
                layout::Dim::One(_) => 1,
                layout::Dim::Two(_) => 2,
            })
            .sum()
    };
    let guided = strategy.directions == vrpt::bsdf::Directions::Guided;
    let bounce = count(&layout::BOUNCE_DIMS)
        + if guided {
            count(&layout::GUIDE_DIMS)
        } else {
            0
        };
    count(&layout::CAMERA_DIMS) + max_depth as usize * bounce
}

/// The factory of a Python sampler's samplers.
fn py_factory(shared: &Arc<PySamplerShared>) -> impl Fn(u64, SamplePass) -> PySampler + Sync {
    let shared = shared.clone();
    move |seed, pass| PySampler {
        shared: shared.clone(),
        seed,
        pass,
        pixel: None,
        values: Vec::new(),
        row: 0,
        dim: 0,
    }
}

/// `vrpt render SCENE FLAGS…` kept in memory, with the built-in sampler or `sampler`.
#[pyfunction]
#[pyo3(signature = (flags, sampler = None))]
fn render(py: Python<'_>, flags: Vec<String>, sampler: Option<Py<PyAny>>) -> PyResult<NativeImage> {
    let stop = Arc::new(AtomicBool::new(false));
    let request = RenderRequest {
        stop: Some(stop.clone()),
        ..commands::parse_flags::<RenderRequest>("render", &flags).map_err(py_err)?
    };
    let job = py.detach(|| request.prepare_in_memory()).map_err(py_err)?;
    for w in &job.scene.warnings {
        warn(py, w)?;
    }
    let shared = sampler.map(|call| {
        Arc::new(PySamplerShared {
            call,
            dims: numbers_per_sample(&job.settings.strategy, job.settings.max_depth),
            failed: Mutex::new(None),
            stop: stop.clone(),
        })
    });
    let (outcome, _) = interruptible(py, &stop, || match &shared {
        Some(s) => job.run_with(&py_factory(s), &NoProgress),
        None => job.run(&NoProgress),
    });
    if let Some(e) = shared.and_then(|s| s.failed.lock().ok()?.take()) {
        return Err(e);
    }
    let outcome = outcome.map_err(py_err)?;
    for w in outcome.warnings() {
        warn(py, &w)?;
    }
    Ok(NativeImage::of_render(outcome))
}

/// Issue a Python `UserWarning` (the CLI prints its warnings to stderr).
fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
    let message = std::ffi::CString::new(message.replace('\0', " "))?;
    PyErr::warn(py, category.as_any(), &message, 2)
}

/// Read a vrpt EXR (or any RGB EXR).
#[pyfunction]
fn read_exr(py: Python<'_>, path: PathBuf) -> PyResult<NativeImage> {
    let image = py
        .detach(|| vrpt::image_io::read_exr(&path))
        .map_err(py_err)?;
    Ok(NativeImage {
        image,
        render: None,
    })
}

/// The experiment's entries for samplers written in Python, named, with the strategy's
/// directions and lights.
fn custom_entries<'a>(
    samplers: &[(String, Arc<PySamplerShared>)],
    strategy: Strategy,
) -> Vec<Entry<'a>> {
    samplers
        .iter()
        .map(|(name, s)| Entry::custom(name, py_factory(s), strategy))
        .collect()
}

/// The shared state of each named Python sampler of an experiment whose paths have
/// `max_depth` segments under `strategy`.
fn py_samplers(
    samplers: Vec<(String, Py<PyAny>)>,
    strategy: &Strategy,
    max_depth: u32,
) -> Vec<(String, Arc<PySamplerShared>)> {
    samplers
        .into_iter()
        .map(|(name, call)| {
            let shared = PySamplerShared {
                call,
                dims: numbers_per_sample(strategy, max_depth),
                failed: Mutex::new(None),
                stop: Arc::new(AtomicBool::new(false)),
            };
            (name, Arc::new(shared))
        })
        .collect()
}

/// The first error of any of the Python samplers.
fn first_failure(samplers: &[(String, Arc<PySamplerShared>)]) -> Option<PyErr> {
    samplers
        .iter()
        .find_map(|(_, s)| s.failed.lock().ok()?.take())
}

/// Run an experiment prepared from flags, with Python samplers (named) beside its strategies,
/// with the directions and lights of `strategy`; its result as JSON.
fn run_experiment<R, T: serde::Serialize + Send>(
    py: Python<'_>,
    prepared: vrpt::Result<experiment::Prepared<R>>,
    (samplers, strategy): (Vec<(String, Py<PyAny>)>, Strategy),
    run: impl FnOnce(experiment::Prepared<R>, Vec<Entry>) -> vrpt::Result<T> + Send,
) -> PyResult<String>
where
    experiment::Prepared<R>: Experiment + Send,
{
    let prepared = prepared.map_err(py_err)?;
    for w in &prepared.scene().warnings {
        warn(py, w)?;
    }
    let shared = py_samplers(samplers, &strategy, prepared.settings.max_depth);
    let never = AtomicBool::new(false);
    let (result, _) = interruptible(py, &never, || {
        run(prepared, custom_entries(&shared, strategy))
    });
    if let Some(e) = first_failure(&shared) {
        return Err(e);
    }
    let result = result.map_err(py_err)?;
    serde_json::to_string(&result).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The strategy whose directions and lights an experiment's Python samplers take: its first.
fn first(e: &experiment::ExperimentRequest) -> Strategy {
    e.strategies.0.first().copied().unwrap_or_default()
}

/// `vrpt compare SCENE FLAGS…` (files only where flags ask), the comparison as JSON.
#[pyfunction]
#[pyo3(signature = (flags, samplers = Vec::new()))]
fn compare(
    py: Python<'_>,
    flags: Vec<String>,
    samplers: Vec<(String, Py<PyAny>)>,
) -> PyResult<String> {
    let request = commands::parse_flags::<experiment::CompareRequest>("compare", &flags);
    let strategy = request
        .as_ref()
        .map_or_else(|_| Strategy::default(), |r| first(&r.experiment));
    let prepared = py.detach(|| request.and_then(|r| r.prepare()));
    run_experiment(py, prepared, (samplers, strategy), |p, custom| {
        Ok(p.run_with(custom, &NoProgress)?.result)
    })
}

/// `vrpt converge SCENE FLAGS…`, the convergence as JSON.
#[pyfunction]
#[pyo3(signature = (flags, samplers = Vec::new()))]
fn converge(
    py: Python<'_>,
    flags: Vec<String>,
    samplers: Vec<(String, Py<PyAny>)>,
) -> PyResult<String> {
    let request = commands::parse_flags::<experiment::ConvergeRequest>("converge", &flags);
    let strategy = request
        .as_ref()
        .map_or_else(|_| Strategy::default(), |r| first(&r.experiment));
    let prepared = py.detach(|| request.and_then(|r| r.prepare()));
    run_experiment(py, prepared, (samplers, strategy), |p, custom| {
        Ok(p.run_with(custom, &NoProgress)?.result)
    })
}

/// `vrpt integrate FLAGS…`, its rows as JSON.
#[pyfunction]
fn integrate(py: Python<'_>, flags: Vec<String>) -> PyResult<String> {
    let request =
        commands::parse_flags::<commands::integrate::IntegrateRequest>("integrate", &flags)
            .map_err(py_err)?;
    let outcome = py
        .detach(|| commands::integrate::run(&request))
        .map_err(py_err)?;
    serde_json::to_string(&outcome.rows).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `n` points of `sampler` in the 2D dimension `dims` of the layout (`pixel`, `light-B`,
/// `direction-B`) of one pixel with seed `seed`, as bytes of `n × 2` `f32`.
#[pyfunction]
fn points<'py>(
    py: Python<'py>,
    sampler: &str,
    n: u32,
    dims: &str,
    seed: u64,
) -> PyResult<Bound<'py, PyBytes>> {
    use clap::ValueEnum;
    let kind = vrpt::sampler::SamplerKind::from_str(sampler, true).map_err(|_| {
        PyValueError::new_err(format!(
            "'{sampler}' is not a sampler: independent, jittered, stratified, sobol"
        ))
    })?;
    let dim = vrpt::analysis::points::dimension_index(dims).ok_or_else(|| {
        PyValueError::new_err(format!(
            "'{dims}' is not a 2D dimension: pixel, light-B or direction-B (B from 1)"
        ))
    })?;
    // as `vrpt points --n`
    if !(1..=4096).contains(&n) {
        return Err(PyValueError::new_err(format!(
            "n = {n}: a set holds 1 to 4096 points"
        )));
    }
    let sets = py.detach(|| commands::points::realisations(kind, seed, n, dim, 1));
    let bytes = f32_bytes(sets[0].iter().flat_map(|p| p.to_array()));
    Ok(PyBytes::new(py, &bytes))
}

/// The metrics of an image against a reference (both `height × width × 3` `f32` bytes): MSE,
/// relMSE, RMSE, MAE, mean signed error, as JSON.
#[pyfunction]
fn diff(image: &[u8], reference: &[u8]) -> PyResult<String> {
    if image.len() != reference.len() || !image.len().is_multiple_of(12) {
        return Err(PyValueError::new_err(format!(
            "the images differ in size ({} and {} bytes of RGB float32)",
            image.len(),
            reference.len()
        )));
    }
    let rgb = |b: &[u8]| -> Vec<Vec3> {
        b.chunks_exact(12)
            .map(|p| {
                let c = |i: usize| f32::from_ne_bytes([p[i], p[i + 1], p[i + 2], p[i + 3]]);
                Vec3::new(c(0), c(4), c(8))
            })
            .collect()
    };
    let m = vrpt::analysis::metrics::metrics(&rgb(image), &rgb(reference));
    serde_json::to_string(&m).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// What each number of a path sample decides, in the order a sampler is asked for them, for
/// paths of `bounces` bounces (a 2D dimension is two numbers, `… u` and `… v`), with the guided
/// directions' three more per bounce if `guided`: the rows a Python sampler fills.
#[pyfunction]
#[pyo3(signature = (bounces, guided = false))]
fn number_names(bounces: u32, guided: bool) -> Vec<String> {
    let mut names = Vec::new();
    let mut push = |d: &layout::Dim, bounce: Option<u32>| {
        let at = bounce.map_or(String::new(), |b| format!(" {b}"));
        match d {
            layout::Dim::One(what) => names.push(format!("{what}{at}")),
            layout::Dim::Two(what) => {
                names.push(format!("{what}{at} u"));
                names.push(format!("{what}{at} v"));
            }
        }
    };
    layout::CAMERA_DIMS.iter().for_each(|d| push(d, None));
    for b in 1..=bounces {
        layout::BOUNCE_DIMS.iter().for_each(|d| push(d, Some(b)));
        if guided {
            layout::GUIDE_DIMS.iter().for_each(|d| push(d, Some(b)));
        }
    }
    names
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<NativeImage>()?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(converge, m)?)?;
    m.add_function(wrap_pyfunction!(integrate, m)?)?;
    m.add_function(wrap_pyfunction!(points, m)?)?;
    m.add_function(wrap_pyfunction!(diff, m)?)?;
    m.add_function(wrap_pyfunction!(number_names, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
