"""Tests of the Python binding: arrays that match the CLI's EXR bit for bit, the metadata, the
errors, the GIL released while rendering, Ctrl-C, samplers written in Python, and the analysis
functions. Run from the repository's root: ``python -m pytest python/tests`` (the CLI binary is
``$VRPT_BIN``, else ``target/debug/vrpt`` as ``cargo test`` builds it)."""

import math
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import vrpt

ROOT = Path(__file__).resolve().parents[2]
CORNELL = str(ROOT / "scenes" / "cornell-box")
SMALL = dict(width=32, height=24)


def cli(*args):
    binary = os.environ.get("VRPT_BIN", str(ROOT / "target" / "debug" / "vrpt"))
    assert Path(binary).exists(), f"the vrpt binary is not at {binary}: build it (cargo build) or set VRPT_BIN"
    return subprocess.run([binary, *args], check=True, capture_output=True, text=True)


def test_the_readme_line_renders_the_cornell_box_at_its_size():
    r = vrpt.render(CORNELL, spp=4)
    assert r.image.shape == (256, 256, 3)
    assert r.image.dtype == np.float32
    assert np.isfinite(r.image).all() and r.image.mean() > 0.01


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        ([], {}),
        (["--directions", "guided", "--replicates", "2"], dict(directions="guided", replicates=2)),
        (["--strategy", "nee", "--adaptive"], dict(strategy="nee", adaptive=True)),
        (["--sampler", "sobol", "--max-depth", "3"], dict(sampler="sobol", max_depth=3)),
        (["--roulette", "ears"], dict(roulette="ears")),
        (["--directions", "guided"], dict(directions="guided")),
        (["--directions", "guided", "--training-images", "discard"], dict(directions="guided", training_images="discard")),
        (["--directions", "guided", "--guide-gate", "off"], dict(directions="guided", guide_gate="off")),
    ],
)
def test_arrays_and_metadata_match_the_cli_exr_bit_for_bit(tmp_path, flags, kwargs):
    exr = tmp_path / "cli.exr"
    cli("render", CORNELL, "--spp", "8", "--width", "32", "--height", "24", "--seed", "3", "-o", str(exr), *flags)
    from_cli = vrpt.read(exr)
    r = vrpt.render(CORNELL, spp=8, seed=3, **SMALL, **kwargs)
    assert r.image.shape == (24, 32, 3)
    assert np.array_equal(r.image.view(np.uint32), from_cli.image.view(np.uint32))
    assert np.array_equal(r.variance.view(np.uint32), from_cli.variance.view(np.uint32))
    assert np.array_equal(r.samples, from_cli.samples)
    if kwargs.get("replicates", 1) > 1:
        assert np.array_equal(r.estimated_variance, from_cli.estimated_variance)
    else:
        assert r.estimated_variance is None or np.array_equal(r.estimated_variance, from_cli.estimated_variance)
    # the same keys, the same values but for the wall times
    a, b = dict(r.metadata), dict(from_cli.metadata)
    assert a.keys() == b.keys()
    times = [k for k in a if k.endswith("_seconds")]
    assert "render_seconds" in times and all(a[k] > 0 and b[k] > 0 for k in times)
    assert {k: v for k, v in a.items() if k not in times} == {k: v for k, v in b.items() if k not in times}
    # and a save is the CLI's file
    saved = tmp_path / "py.exr"
    r.save(saved)
    assert np.array_equal(vrpt.read(saved).image, from_cli.image)


def test_metadata_names_what_rendered():
    r = vrpt.render(CORNELL, spp=8, seed=5, replicates=2, **SMALL)
    m = r.metadata
    for key in ["scene", "scene_hash", "width", "height", "spp", "seed", "strategy", "sampler", "max_depth", "replicates", "estimated_rel_mse"]:
        assert key in m, key
    assert (m["width"], m["height"], m["spp"], m["seed"], m["replicates"]) == (32, 24, 8, 5, 2)
    assert r.spp == 8 and r.seconds > 0
    assert 0 < r.estimated_rel_mse < 10
    assert "Mrays/s" in r.summary or "rays" in r.summary


def test_auto_renders_the_strategy_its_pilots_chose():
    auto = vrpt.render(CORNELL, strategy="auto", auto_candidates="independent,mis", spp=32, seed=4, **SMALL)
    mis = vrpt.render(CORNELL, strategy="mis", spp=32, seed=4, **SMALL)
    assert auto.metadata["auto"].startswith("chose mis;")
    assert "<- chosen" in auto.summary
    assert np.array_equal(auto.image, mis.image)
    # path reuse as a candidate, first: kept (it is the more efficient on the box), rendered as reuse=4
    auto = vrpt.render(CORNELL, strategy="auto", auto_candidates=["mis+reuse4", "mis"], spp=32, seed=4, **SMALL)
    reused = vrpt.render(CORNELL, strategy="mis", reuse=4, spp=32, seed=4, **SMALL)
    assert auto.metadata["auto"].startswith("chose mis+reuse4;")
    assert np.array_equal(auto.image, reused.image)


def test_errors_are_python_exceptions_with_the_cli_messages(tmp_path):
    with pytest.raises(FileNotFoundError, match="no-such-scene"):
        vrpt.render(str(tmp_path / "no-such-scene.obj"))
    with pytest.raises(ValueError, match="spp"):
        vrpt.render(CORNELL, spp=0)
    with pytest.raises(ValueError, match="strategy"):
        vrpt.render(CORNELL, strategy="no-such-strategy")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 9\n")
    with pytest.raises(ValueError, match="bad.obj"):
        vrpt.render(bad, spp=1)
    r = vrpt.render(CORNELL, spp=1, width=8, height=8)
    with pytest.raises(OSError):
        r.save(tmp_path / "no-such-folder" / "x.exr")
    with pytest.raises(OSError, match="unknown image format"):
        r.save(tmp_path / "x.bmp")
    with pytest.raises(TypeError):
        vrpt.render(CORNELL, no_such_argument=1)
    with pytest.raises(ValueError, match="not a sampler"):
        vrpt.points("no-such-sampler", 16)


def test_the_gil_is_released_while_rendering():
    counts = []
    done = threading.Event()

    def count():
        n = 0
        while not done.is_set():
            n += 1
            time.sleep(0.001)
        counts.append(n)

    t = threading.Thread(target=count)
    t.start()
    start = time.monotonic()
    vrpt.render(CORNELL, spp=64, width=64, height=64)
    seconds = time.monotonic() - start
    done.set()
    t.join()
    # a thread sleeping 1 ms per step takes about one step per 1.1 ms when it may run; held
    # out by the GIL it would take none during the render. A tenth of that rate is the bound.
    assert seconds > 0.05, "the render was too short to tell"
    assert counts[0] > 0.1 * seconds / 0.0011, (counts, seconds)


def test_ctrl_c_stops_a_render_and_returns_the_samples_taken():
    # Python's own Ctrl-C handler (a process started in the background of a shell inherits
    # SIGINT ignored, and Python then installs none)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
        timer.start()
        start = time.monotonic()
        # uninterrupted, 300000 spp of 16×16 pixels take a minute or more on 2 cores
        with pytest.warns(UserWarning, match="interrupted"):
            r = vrpt.render(CORNELL, spp=300_000, width=16, height=16, pass_spp=1)
        seconds = time.monotonic() - start
        timer.join()
    finally:
        signal.signal(signal.SIGINT, previous)
    assert r.interrupted
    assert 1 <= r.spp < 300_000
    assert r.metadata["interrupted"] is True
    assert np.isfinite(r.image).all() and r.image.mean() > 0
    assert seconds < 10


def iid_sampler(pixel, first, n, dims, seed):
    rng = np.random.default_rng([seed, pixel[0], pixel[1], first])
    return rng.random((n, dims))


def image_mean_and_variance(r):
    """The mean of the image over pixels and channels, and the variance of that mean: the
    pixels' means are independent (each pixel draws its own numbers), so it is the sum of
    their variances over (3·pixels)²."""
    count = r.image.size
    return float(r.image.astype(np.float64).mean()), float(r.variance.astype(np.float64).sum() / count**2)


def test_a_sampler_written_in_python_renders_unbiased_and_a_biased_one_is_caught():
    calls = []

    def recording(pixel, first, n, dims, seed):
        calls.append((pixel, first, n, dims))
        return iid_sampler(pixel, first, n, dims, seed)

    settings = dict(spp=16, width=24, height=24, seed=2)
    mine = vrpt.render(CORNELL, sampler=recording, **settings)
    builtin = vrpt.render(CORNELL, sampler="independent", **settings)
    # one call per pixel (one pass of 16), asking for every number a path of 8 bounces draws
    assert len(calls) == 24 * 24
    assert {c[0] for c in calls} == {(x, y) for x in range(24) for y in range(24)}
    assert {c[1:] for c in calls} == {(0, 16, len(vrpt.number_names(8)))}
    (m1, v1), (m2, v2) = image_mean_and_variance(mine), image_mean_and_variance(builtin)
    # |z| < 5: a false alarm has probability below 1e-6 for a normal z; 576 pixels × 3
    # channels × 16 samples make the image mean near normal (the Kish ESS of the pixel means is
    # in the hundreds for this box)
    z = (m1 - m2) / math.sqrt(v1 + v2)
    assert abs(z) < 5, z

    def squeezed(pixel, first, n, dims, seed):
        return 0.5 * iid_sampler(pixel, first, n, dims, seed)

    biased = vrpt.render(CORNELL, sampler=squeezed, **settings)
    m3, v3 = image_mean_and_variance(biased)
    assert abs(m3 - m2) / math.sqrt(v3 + v2) > 5


def test_a_sampler_that_returns_the_wrong_shape_is_refused():
    def wrong(pixel, first, n, dims, seed):
        return np.zeros((n, 3))

    with pytest.raises(ValueError, match="shape"):
        vrpt.render(CORNELL, sampler=wrong, spp=4, width=8, height=8)

    def raises(pixel, first, n, dims, seed):
        raise RuntimeError("my sampler broke")

    with pytest.raises(RuntimeError, match="my sampler broke"):
        vrpt.render(CORNELL, sampler=raises, spp=4, width=8, height=8)


def test_points_are_the_samplers_sets():
    for name in ["independent", "jittered", "stratified", "sobol"]:
        p = vrpt.points(name, 64, seed=3)
        assert p.shape == (64, 2) and p.dtype == np.float32
        assert ((p >= 0) & (p < 1)).all()
        assert np.array_equal(p, vrpt.points(name, 64, seed=3))
    # the jittered set of 16 has one point in each cell of the 4×4 grid
    cells = {(int(x * 4), int(y * 4)) for x, y in vrpt.points("jittered", 16)}
    assert len(cells) == 16
    assert len(vrpt.points("independent", 16, dims="direction-2")) == 16


def test_integrate_gives_rows_with_the_predicted_variance():
    rows = vrpt.integrate(integrand="disk", sampler=["independent", "jittered"], n=16, repetitions=400)
    measured = [r for r in rows if r.get("variance") is not None]
    assert {r["sampler"] for r in measured} == {"independent", "jittered"}
    for r in measured:
        assert r["predicted_variance"] > 0 and r["variance"] > 0


def test_diff_measures_arrays_renders_and_files(tmp_path):
    a = vrpt.render(CORNELL, spp=4, **SMALL)
    assert vrpt.diff(a, a.image)["mse"] == 0
    m = vrpt.diff(a.image + 1.0, a)
    assert m["mse"] == pytest.approx(1.0, rel=1e-6) and m["mean_signed_error"] == pytest.approx(1.0, rel=1e-6)
    a.save(tmp_path / "a.exr")
    assert vrpt.diff(tmp_path / "a.exr", a)["mse"] == 0
    with pytest.raises(ValueError, match="size"):
        vrpt.diff(a, np.zeros((2, 2, 3)))


def test_compare_and_converge_take_a_render_as_reference_and_python_samplers():
    reference = vrpt.render(CORNELL, spp=64, width=16, height=16, seed=100)
    rows = vrpt.compare(
        CORNELL, reference, strategies="independent,stratified", samplers={"mine": iid_sampler}, spp=4, runs=2
    )
    assert rows.column("strategy") == ["independent", "stratified", "mine"]
    assert rows.baseline == "independent"
    assert all(r["mse"] > 0 and r["seconds"] > 0 for r in rows)
    c = vrpt.converge(CORNELL, reference, strategies=["independent"], spp=[1, 4], runs=2)
    assert [(p["strategy"], p["spp"]) for p in c] == [("independent", 1), ("independent", 4)]
    assert c.slopes[0]["strategy"] == "independent"
