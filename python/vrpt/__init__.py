"""vrpt from Python: render, compare and measure variance reduction, numpy in and out.

A thin layer over the vrpt library (Rust): every function here turns its keyword arguments into
the flags of the matching ``vrpt`` command, and the library parses and runs them exactly as the
command line does: the same defaults, the same checks, the same one-line messages, and for the
same seed the same image, bit for bit.

>>> import vrpt
>>> r = vrpt.render("scenes/cornell-box", spp=4)
>>> r.image.shape
(256, 256, 3)

Images are ``height × width × 3`` float32 arrays (linear radiance, rows from the top). Tables
are lists of dicts. Errors are ``FileNotFoundError`` (a missing file), ``OSError`` (a file that
cannot be read or written) and ``ValueError`` (bad input: a malformed scene, a bad value).
While vrpt works the GIL is released, so other Python threads run; Ctrl-C stops a render after
its current batch of samples and returns the image of the samples taken (``interrupted`` says
so), as ``vrpt render`` writes them.
"""

from __future__ import annotations

import json
import os
import re
import tempfile
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native

__version__ = _native.__version__
__all__ = [
    "Render",
    "Rows",
    "render",
    "read",
    "compare",
    "converge",
    "points",
    "integrate",
    "diff",
    "number_names",
]

PathLike = Union[str, "os.PathLike[str]"]
#: A sampler written in Python: ``f(pixel=(x, y), first=i0, n=n, dims=d, seed=s)`` returns the
#: numbers of one pixel's set of ``n`` samples (sample indices ``i0 .. i0 + n``), an ``n × d``
#: array of floats in ``[0, 1)``; row ``i`` feeds sample ``i0 + i`` in vrpt's dimension order
#: (``number_names``). ``index % n`` is a sample's place in its set.
SamplerFunction = Callable[..., Any]


def _flag_value(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return ",".join(_flag_value(v) for v in value)
    return str(value)


def _flags(**kwargs: Any) -> List[str]:
    """Keyword arguments as command-line flags: ``spp=64`` is ``--spp 64``, ``adaptive=True`` is
    ``--adaptive``; ``None`` and ``False`` are left out (the command's default)."""
    out: List[str] = []
    for key, value in kwargs.items():
        if value is None or value is False:
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            out.append(flag)
        else:
            out += [flag, _flag_value(value)]
    return out


_FLAG = re.compile(r"'--([a-z][a-z0-9-]*)(?: <[^>]*>)?'")


def _pythonic(error: Exception) -> Exception:
    """The library's message with its flags named as this module's keywords
    (``'--spp <SPP>'`` becomes ``spp``)."""
    text = _FLAG.sub(lambda m: m.group(1).replace("-", "_"), str(error))
    return type(error)(text)


def _call(function: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    try:
        return function(*args, **kwargs)
    except ValueError as e:
        raise _pythonic(e) from None


def _rgb(data: Optional[bytes], height: int, width: int) -> Optional[np.ndarray]:
    if data is None:
        return None
    return np.frombuffer(data, dtype=np.float32).reshape(height, width, 3).copy()


def _typed(value: str) -> Any:
    """A metadata value as the number it writes, where it is one."""
    for kind in (int, float):
        try:
            return kind(value)
        except ValueError:
            pass
    if value in ("true", "false"):
        return value == "true"
    return value


class Render:
    """An image as vrpt writes it to an EXR: the mean, the variance of each pixel's mean, the
    samples per pixel, the replicates' estimated variance, and the metadata; for a render, also
    what it said (``summary``, ``warnings``) and ``save``.

    Arrays are made once, on first use, and are the caller's to change.
    """

    def __init__(self, native: Any) -> None:
        self._native = native
        self._cache: Dict[str, Any] = {}

    def _cached(self, key: str, make: Callable[[], Any]) -> Any:
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    @property
    def width(self) -> int:
        return self._native.width

    @property
    def height(self) -> int:
        return self._native.height

    @property
    def image(self) -> np.ndarray:
        """The mean: ``height × width × 3`` float32, linear radiance, rows from the top."""
        n = self._native
        return self._cached("image", lambda: _rgb(n.pixels(), n.height, n.width))

    @property
    def variance(self) -> Optional[np.ndarray]:
        """The variance of each pixel's mean from its samples (``s²/n``), or ``None``."""
        n = self._native
        return self._cached("variance", lambda: _rgb(n.variance(), n.height, n.width))

    @property
    def estimated_variance(self) -> Optional[np.ndarray]:
        """The variance of each pixel's mean estimated from the replicates' spread (honest for
        every sampler), or ``None`` with one replicate."""
        n = self._native
        return self._cached("estimated_variance", lambda: _rgb(n.estimated_variance(), n.height, n.width))

    @property
    def samples(self) -> Optional[np.ndarray]:
        """Samples in each pixel's mean, ``height × width`` uint32, or ``None``."""
        n = self._native

        def make() -> Optional[np.ndarray]:
            data = n.samples()
            if data is None:
                return None
            return np.frombuffer(data, dtype=np.uint32).reshape(n.height, n.width).copy()

        return self._cached("samples", make)

    @property
    def metadata(self) -> Dict[str, Any]:
        """The EXR's metadata (keys without its ``vrpt.`` prefix), numbers as numbers."""
        return self._cached("metadata", lambda: {k: _typed(v) for k, v in self._native.metadata().items()})

    @property
    def estimated_rel_mse(self) -> Optional[float]:
        """The image's relMSE as the render estimated it (from its replicates, or per sample),
        or ``None`` where it was not estimated."""
        value = self.metadata.get("estimated_rel_mse")
        return None if value is None else float(value)

    @property
    def spp(self) -> int:
        """Samples per pixel rendered."""
        return int(self.metadata.get("spp", 0))

    @property
    def seconds(self) -> Optional[float]:
        """Wall seconds of the render."""
        value = self.metadata.get("render_seconds")
        return None if value is None else float(value)

    @property
    def summary(self) -> str:
        """What ``vrpt render`` prints: the scene, the speed, the rays, the error."""
        return self._native.summary

    @property
    def timing(self) -> str:
        """Where the time went (``stats=True`` times the phases)."""
        return self._native.timing

    @property
    def warnings(self) -> List[str]:
        """What the render warned of (also issued as Python warnings)."""
        return list(self._native.warnings)

    @property
    def interrupted(self) -> bool:
        """Whether Ctrl-C (or a failing Python sampler) ended the render early."""
        return self._native.interrupted

    def save(self, path: PathLike, exposure: float = 0.0, variance: Optional[PathLike] = None) -> None:
        """Write the render as ``vrpt render -o PATH`` does: ``.exr`` (linear, with the variance
        channels and metadata) or ``.png`` (tone-mapped, ``exposure`` in stops); ``variance``
        also writes the variance of the mean to that EXR."""
        _call(self._native.save, os.fspath(path), exposure, None if variance is None else os.fspath(variance))

    def __repr__(self) -> str:
        m = self.metadata
        return f"<vrpt.Render {self.width}x{self.height}, {m.get('spp')} spp, {m.get('strategy')}, {m.get('scene')}>"


def _sampler_function(user: SamplerFunction) -> Callable[..., bytes]:
    """Wrap a user's sampler: call it, check its ``n × dims`` numbers, give float32 bytes."""

    def call(pixel: Tuple[int, int], first: int, n: int, dims: int, seed: int) -> bytes:
        values = np.asarray(user(pixel=pixel, first=first, n=n, dims=dims, seed=seed), dtype=np.float64)
        if values.shape != (n, dims):
            raise ValueError(
                f"the sampler returned an array of shape {values.shape} for pixel {pixel}, "
                f"not ({n}, {dims}): n samples, dims numbers each"
            )
        if not np.all((values >= 0.0) & (values < 1.0)):
            raise ValueError(f"the sampler returned numbers outside [0, 1) for pixel {pixel}")
        return values.astype(np.float32).tobytes()

    return call


def render(
    scene: PathLike,
    *,
    spp: Optional[int] = None,
    seed: int = 0,
    strategy: Optional[str] = None,
    sampler: Union[None, str, SamplerFunction] = None,
    directions: Optional[str] = None,
    lights: Optional[str] = None,
    light_points: Optional[str] = None,
    light_choice: Optional[str] = None,
    auto_candidates: Union[None, str, Sequence[str]] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    max_depth: Optional[int] = None,
    time_limit: Optional[float] = None,
    pass_spp: Optional[int] = None,
    first_sample: int = 0,
    shard: Optional[Tuple[int, int]] = None,
    replicates: Optional[int] = None,
    adaptive: bool = False,
    min_allocation_gain: Optional[float] = None,
    target_error: Optional[float] = None,
    reuse: Optional[int] = None,
    roulette: Optional[str] = None,
    edge_rays: Optional[int] = None,
    training_images: Optional[str] = None,
    guide_gate: Optional[str] = None,
    threads: Optional[int] = None,
    strict: bool = False,
    stats: bool = False,
) -> Render:
    """Render ``scene`` (an .obj, a scene.toml, or a folder holding one) and return the image.

    Each argument is the ``vrpt render`` flag of its name (``vrpt render --help`` says what each
    does); ``None`` takes the scene's ``[render]`` default, then vrpt's. ``strategy`` is a preset
    (``independent``, ``stratified``, ``importance``, ``combined``, ``nee``, ``mis``; default:
    vrpt's default) or ``auto`` (a pilot chooses among ``auto_candidates``, strategies with
    ``+reuseK`` for path reuse or ``+ears`` for EARS such as ``"mis,mis+reuse4"``; the default
    ``"mis,mis+reuse4,stratified+guided+mis,stratified+guided+mis+reuse4"``, the guided twin of
    the unguided choice rendered with its gate, not piloted, where reuse wins or light is caustic;
    what it measured is in
    ``summary`` and ``metadata["auto"]``), and ``sampler``, ``directions`` (``guided`` for path
    guiding), ``lights``, ``light_points``, ``light_choice`` set one part of it. ``roulette`` is
    ``classic`` or ``ears`` (efficiency-aware roulette and splitting, learned while rendering).
    ``edge_rays`` is the most camera rays a sample spends on the emission seen directly in a
    pixel along the edge of a light, each pixel's count chosen by a pilot (default 256; 0: off).
    ``training_images`` (guided directions only) is ``keep`` (the default: the last training
    iterations are combined into the image by inverse variance) or ``discard``; ``guide_gate``
    (guided directions only) is ``on`` (the default: probes during training render the rest
    without the guide where it loses) or ``off``.
    ``sampler`` may also be a function of your own (see ``SamplerFunction``): slow, since Python
    draws every number, but rendered through the same entry as vrpt's samplers. ``shard`` is
    ``(i, n)``. The image is kept in memory; ``Render.save`` writes it.
    """
    custom = sampler if callable(sampler) else None
    flags = [os.fspath(scene)] + _flags(
        spp=spp,
        seed=seed,
        strategy=strategy,
        sampler=None if custom else sampler,
        directions=directions,
        lights=lights,
        light_points=light_points,
        light_choice=light_choice,
        auto_candidates=auto_candidates,
        width=width,
        height=height,
        max_depth=max_depth,
        time_limit=time_limit,
        pass_spp=pass_spp,
        first_sample=first_sample,
        shard=None if shard is None else f"{shard[0]}/{shard[1]}",
        replicates=replicates,
        adaptive=adaptive,
        min_allocation_gain=min_allocation_gain,
        target_error=target_error,
        reuse=reuse,
        roulette=roulette,
        edge_rays=edge_rays,
        training_images=training_images,
        guide_gate=guide_gate,
        threads=threads,
        strict=strict,
        stats=stats,
    )
    native = _call(_native.render, flags, _sampler_function(custom) if custom else None)
    return Render(native)


def read(path: PathLike) -> Render:
    """Read an EXR (a vrpt render, a merge, or any RGB EXR) as a ``Render``."""
    return Render(_call(_native.read_exr, os.fspath(path)))


class Rows(list):
    """A table: a list of dicts, one per row, with what else the experiment measured as
    attributes (``extras``)."""

    def __init__(self, rows: Iterable[Dict[str, Any]], **extras: Any) -> None:
        super().__init__(rows)
        self.extras = extras
        for key, value in extras.items():
            setattr(self, key, value)

    def column(self, name: str) -> List[Any]:
        """One column, in row order."""
        return [row[name] for row in self]


class _Reference:
    """A reference given as a path, or as a ``Render`` (saved to a temporary EXR)."""

    def __init__(self, reference: Union[PathLike, Render]) -> None:
        self._dir: Optional[tempfile.TemporaryDirectory] = None
        if isinstance(reference, Render):
            self._dir = tempfile.TemporaryDirectory(prefix="vrpt-reference-")
            self.path = os.path.join(self._dir.name, "reference.exr")
            reference.save(self.path)
        else:
            self.path = os.fspath(reference)

    def __enter__(self) -> str:
        return self.path

    def __exit__(self, *exc: Any) -> None:
        if self._dir is not None:
            self._dir.cleanup()


def _experiment_flags(
    scene: PathLike,
    reference: str,
    strategies: Union[None, str, Sequence[str]],
    **kwargs: Any,
) -> List[str]:
    return [os.fspath(scene)] + _flags(reference=reference, strategies=strategies, **kwargs)


def _named_samplers(samplers: Optional[Mapping[str, SamplerFunction]]) -> List[Tuple[str, Callable[..., bytes]]]:
    return [(name, _sampler_function(f)) for name, f in (samplers or {}).items()]


def compare(
    scene: PathLike,
    reference: Union[PathLike, Render],
    *,
    strategies: Union[None, str, Sequence[str]] = None,
    samplers: Optional[Mapping[str, SamplerFunction]] = None,
    spp: int = 16,
    equal_time: Optional[float] = None,
    runs: int = 8,
    seed: int = 1,
    replicates: Optional[int] = None,
    adaptive: bool = False,
    threads: Optional[int] = None,
    regions: Optional[Sequence[str]] = None,
    strict: bool = False,
) -> Rows:
    """``vrpt compare``: each strategy (default: the six presets) at ``spp`` samples per pixel,
    or ``equal_time`` seconds per run, over ``runs`` independent runs against ``reference`` (an
    EXR path, or a ``Render``). ``samplers`` adds samplers of your own by name (with the first
    strategy's directions and lights). One row per entry: ``strategy``, ``spp``, ``seconds``,
    ``mse``, ``rel_mse``, ``variance``, ``est_mse``, ``bias_t``, ``bias_p``, ``mse_reduction``,
    ``efficiency``, …; ``Rows.regions`` holds the rows per region (``regions``: ``"NAME=X,Y,W,H"``
    strings), ``Rows.baseline`` the baseline's name."""
    with _Reference(reference) as ref:
        flags = _experiment_flags(
            scene,
            ref,
            strategies,
            spp=spp,
            equal_time=equal_time,
            runs=runs,
            seed=seed,
            replicates=replicates,
            adaptive=adaptive,
            threads=threads,
            strict=strict,
        )
        for r in regions or []:
            flags += ["--region", r]
        result = json.loads(_call(_native.compare, flags, _named_samplers(samplers)))
    return Rows(
        result["rows"],
        regions=result["regions"],
        baseline=result["baseline"],
        reference_variance=result["reference_variance"],
    )


def converge(
    scene: PathLike,
    reference: Union[PathLike, Render],
    *,
    strategies: Union[None, str, Sequence[str]] = None,
    samplers: Optional[Mapping[str, SamplerFunction]] = None,
    spp: Sequence[int] = (1, 4, 16, 64, 256),
    runs: int = 8,
    seed: int = 1,
    replicates: Optional[int] = None,
    adaptive: bool = False,
    threads: Optional[int] = None,
    strict: bool = False,
) -> Rows:
    """``vrpt converge``: each strategy at each spp, rendered from scratch ``runs`` times. One row
    per (strategy, spp): ``strategy``, ``spp``, ``mse``, ``rel_mse``, ``seconds``, ``est_mse``,
    ``est_rel_mse``; ``Rows.slopes`` the fitted log-log slopes per strategy."""
    with _Reference(reference) as ref:
        flags = _experiment_flags(
            scene,
            ref,
            strategies,
            spp=list(spp),
            runs=runs,
            seed=seed,
            replicates=replicates,
            adaptive=adaptive,
            threads=threads,
            strict=strict,
        )
        result = json.loads(_call(_native.converge, flags, _named_samplers(samplers)))
    return Rows(result["points"], slopes=result["slopes"])


def points(sampler: str, n: int, dims: str = "pixel", seed: int = 0) -> np.ndarray:
    """``n`` points of a built-in sampler (``independent``, ``jittered``, ``stratified``,
    ``sobol``) in one 2D dimension of a path sample (``pixel``, ``light-B``, ``direction-B``;
    bounce B from 1), as vrpt draws them for one pixel: an ``n × 2`` float32 array in
    ``[0, 1)²``."""
    data = _call(_native.points, sampler, int(n), dims, int(seed))
    return np.frombuffer(data, dtype=np.float32).reshape(int(n), 2).copy()


def integrate(
    *,
    integrand: Union[None, str, Sequence[str]] = None,
    sampler: Union[None, str, Sequence[str]] = None,
    n: Union[None, int, Sequence[int]] = None,
    repetitions: Optional[int] = None,
    seed: Optional[int] = None,
) -> Rows:
    """``vrpt integrate``: known-answer integrals (``curve``, ``smooth``, ``disk``, ``cosine``,
    ``lobe``) estimated by each sampler at each ``n``, ``repetitions`` times, beside the
    variance the lecture's formulas predict. One row per estimate (``mean``, ``variance``,
    ``predicted_variance``, ``z``, …) and per covariance of two samples (``covariance``)."""
    flags = _flags(integrand=integrand, sampler=sampler, n=n, repetitions=repetitions, seed=seed)
    return Rows(json.loads(_call(_native.integrate, flags)))


def _image_array(x: Union[np.ndarray, Render, PathLike]) -> np.ndarray:
    if isinstance(x, Render):
        return x.image
    if isinstance(x, (str, os.PathLike)):
        return read(x).image
    a = np.asarray(x, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"an image is height × width × 3, not {a.shape}")
    return a


def diff(image: Union[np.ndarray, Render, PathLike], reference: Union[np.ndarray, Render, PathLike]) -> Dict[str, float]:
    """The error of ``image`` against ``reference`` (arrays ``height × width × 3``, renders, or
    EXR paths) as ``vrpt diff`` computes it: ``mse``, ``rel_mse`` (``(x − r)²/(r² + 0.01)``),
    ``rmse``, ``mae``, ``mean_signed_error``."""
    a, b = _image_array(image), _image_array(reference)
    if a.shape != b.shape:
        raise ValueError(f"the images differ in size: {a.shape} and {b.shape}")
    return json.loads(
        _call(_native.diff, np.ascontiguousarray(a, dtype=np.float32).tobytes(), np.ascontiguousarray(b, dtype=np.float32).tobytes())
    )


def number_names(bounces: int = 2, guided: bool = False) -> List[str]:
    """What each number of a path sample decides, in the order a sampler's rows hold them: the
    pixel position, then per bounce the light choice, the point on the light, the lobe choice,
    the direction and Russian roulette (and, with ``guided``, the guide's three), for paths of
    ``bounces`` bounces. A 2D dimension is two numbers, ``… u`` and ``… v``."""
    return list(_native.number_names(int(bounces), bool(guided)))
