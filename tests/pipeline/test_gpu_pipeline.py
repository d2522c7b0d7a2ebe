"""The tile pipeline: CUDA buffers pooled across calls, chunks sized for the device, and the
sweep computing tile i+1 while it writes tile i.

CUDA checks run in numba's simulator in a subprocess (NUMBA_ENABLE_CUDASIM must be set before
numba.cuda is first imported; see tests/kernels/test_cuda.py); the pooled buffers must give labels
*identical* to the CPU kernel's, for the reason given there. The look-ahead checks run the
CPU sweep in process and compare it with the same sweep computed one tile at a time.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

import atlas
from atlas.errors import StorageError
from atlas.kernels.cuda_host import CHUNK_CAP, MEMORY_FRACTION, WAVES, chunk_orbits
from atlas.pipeline import schedule
from atlas.store.partial import TileStore
from atlas.store.reader import describe
from tests.helpers import write_config
from tests.kernels.test_cuda import _child

# ------------------------------------------------------------------ chunk size

H200 = 132 * 2048  # multiprocessors × resident threads per multiprocessor
BYTES = 25  # per orbit, labelling: θ0, θ̇0 (f8), attractor, n_trap (i4), status (i1)


def test_a_chunk_is_a_few_waves_of_the_device_in_whole_blocks():
    size = chunk_orbits(H200, free_bytes=140e9, bytes_per_orbit=BYTES, block=128)
    assert size == WAVES * H200 and size % 128 == 0
    small_gpu = 20 * 1536
    assert chunk_orbits(small_gpu, 8e9, BYTES, 256) == WAVES * small_gpu // 256 * 256


def test_a_chunk_fits_free_memory_twice():
    free = 10e6  # [B]: memory, not the device, decides
    size = chunk_orbits(H200, free, BYTES, block=128)
    assert 2 * size * BYTES <= MEMORY_FRACTION * free < 2 * (size + 128) * BYTES
    assert size % 128 == 0
    assert chunk_orbits(H200, 1.0, BYTES, block=128) == 128  # at least one block


def test_an_explicit_cap_or_no_device_to_ask():
    assert chunk_orbits(H200, 140e9, BYTES, block=128, cap=37) == 37  # not rounded
    assert chunk_orbits(H200, 1000.0, BYTES, block=128, cap=37) == 10  # memory still bounds
    assert chunk_orbits(None, float("inf"), BYTES, block=128) == CHUNK_CAP  # simulator


# ------------------------------------------------------------------ pooled buffers

POOL = r"""
import json
import numpy as np
from atlas.kernels.cuda import cuda_status
assert cuda_status() == (True, "CUDA simulator"), cuda_status()
from numba import cuda
from atlas.kernels.cuda_host import label_cuda, propagate_cuda
from atlas.kernels.rk4 import label_straightforward, propagate_straightforward
from atlas.labels.trap import CHECK_EVERY, energy_cap, n_checks_for

made = {"pinned_array": 0, "device_array": 0, "stream": 0}
for name in made:
    def counted(*a, _real=getattr(cuda, name), _name=name, **k):
        made[_name] += 1
        return _real(*a, **k)
    setattr(cuda, name, counted)

alpha, omega0, dt, t_max = 0.1, 1.0, 0.01, 5.0
args = (alpha, omega0, dt, n_checks_for(t_max, dt, CHECK_EVERY), CHECK_EVERY,
        energy_cap(dt, alpha, omega0))
failures, after = [], []
# smaller after larger and larger after smaller, one chunk (no cap) and several (cap 16)
for n, chunk in [(12, None), (40, 16), (30, None), (5, None), (40, 16)]:
    theta0 = np.linspace(-3 * np.pi, 3 * np.pi, n) + 0.1
    theta_dot0 = np.linspace(4.0, -4.0, n)
    out = {}
    for name, kernel, kw in [("cpu", label_straightforward, {}),
                             ("gpu", label_cuda, {"chunk": chunk})]:
        res = (np.full(n, 12345, np.int32), np.full(n, 9, np.int8), np.full(n, 7, np.int32))
        kernel(theta0, theta_dot0, *args, *res, **kw)
        out[name] = res
    for field, a, b in zip(("attractor", "status", "n_trap"), out["gpu"], out["cpu"]):
        if not np.array_equal(a, b):
            failures.append(f"n={n} chunk={chunk}: {field} {a.tolist()} vs CPU {b.tolist()}")
    after.append(dict(made))
th, v = np.linspace(-3.0, 3.0, 20), np.linspace(2.0, -2.0, 20)
ref_th, ref_v = th.copy(), v.copy()
propagate_straightforward(ref_th, ref_v, alpha, omega0, dt, 50)
propagate_cuda(th, v, alpha, omega0, dt, 50)  # float64 slots 0 and 1: the labels' own
print(json.dumps({"failures": failures, "made": after, "after_propagate": made,
                  "prop_err": float(max(abs(th - ref_th).max(), abs(v - ref_v).max()))}))
"""


@pytest.mark.slow
def test_pooled_buffers_are_reused_and_label_like_the_cpu_kernel():
    out = _child(POOL, simulator=True)
    assert out["failures"] == []
    # five per-orbit arrays (θ0, θ̇0, attractor, status, n_trap) per buffer set; a set grows
    # only when a call needs more than it holds: 12 (set 0), 16 (set 0 grows, set 1 made),
    # 30 (set 0 grows), then 5 and 16 fit
    pinned = [m["pinned_array"] for m in out["made"]]
    assert pinned == [5, 15, 20, 20, 20]
    assert [m["device_array"] for m in out["made"]] == pinned
    assert [m["stream"] for m in out["made"]] == [1, 2, 2, 2, 2]
    assert out["after_propagate"] == out["made"][-1]  # 20 orbits fit the labels' buffers
    assert out["prop_err"] < 1e-9


# ------------------------------------------------------------------ look-ahead sweep

MANY = """\
grid:
  theta0: {{start: -3pi, stop: 3pi, num: 24}}
  theta_dot0: {{start: -4, stop: 4, num: 16}}
integrator: {{dt: 0.01, t_max: 60}}
separatrices: {{enabled: false}}
execution: {{tile_orbits: 48, backend: {backend}}}
output: {output}
"""
VARIABLES = ("attractor", "status", "t_trap", "boundary_distance", "basin_fraction")


def _config(tmp_path, name="look.h5", backend="cpu"):
    path = write_config(tmp_path / f"{name}.yaml",
                        MANY.format(output=tmp_path / name, backend=backend))
    return atlas.load_config(path)


def _sequential(cfg, tiles, points, todo, device):
    """The sweep as it was: each tile computed when the one before is written."""
    for index in todo:
        yield index, schedule.compute_tile(
            *schedule.tile_args(cfg, tiles.layout, points, index), backend=device)


def _arrays(tree):
    ds = tree.to_dataset(inherit=False)
    return {name: ds[name].values for name in VARIABLES}


@pytest.fixture
def reference(tmp_path, monkeypatch):
    """The arrays of the 8-tile atlas computed one tile at a time."""
    with monkeypatch.context() as m:
        m.setitem(schedule.SCHEDULERS, "local",
                  schedule.Scheduler(_sequential, lambda tiles: False))
        return _arrays(atlas.run(_config(tmp_path, "sequential.h5"), quiet=True))


def _spy(monkeypatch):
    """Record tile computations and writes, in order; each write of tile i waits (5 s at
    most) until tile i + 1 has started computing, which only a look-ahead does."""
    events, started = [], {}
    compute, write = schedule.label_tile, TileStore.write

    def computing(point, x0, v0, rows, *args, **kwargs):
        index = rows.start // 2  # 2 rows per tile, one parameter point
        events.append(("compute", index))
        started.setdefault(index, threading.Event()).set()
        return compute(point, x0, v0, rows, *args, **kwargs)

    def writing(self, index, *args):
        if index + 1 < self.layout.n_tiles:
            events.append(("overlap", index,
                           started.setdefault(index + 1, threading.Event()).wait(5.0)))
        write(self, index, *args)
        events.append(("write", index))

    monkeypatch.setattr(schedule, "label_tile", computing)
    monkeypatch.setattr(TileStore, "write", writing)
    return events


@pytest.mark.slow
def test_the_look_ahead_writes_what_a_sequential_sweep_writes(tmp_path, monkeypatch,
                                                              reference):
    events = _spy(monkeypatch)
    got = _arrays(atlas.run(_config(tmp_path), quiet=True))
    for name in VARIABLES:
        np.testing.assert_array_equal(got[name], reference[name], err_msg=name)
    computed = [e[1] for e in events if e[0] == "compute"]
    written = [e[1] for e in events if e[0] == "write"]
    assert computed == written == list(range(8))
    # tile i + 1 was computing while tile i was written, and never more than one tile ahead
    assert all(e[2] for e in events if e[0] == "overlap")
    for position, event in enumerate(events):
        if event[0] == "compute":
            done = sum(1 for e in events[:position] if e[0] == "write")
            assert done >= event[1] - 1, events


@pytest.mark.slow
def test_tile_i_is_certified_while_tile_i_plus_1_is_labelled(tmp_path, monkeypatch,
                                                             reference):
    """Under a threading layer that runs two parallel kernels at once, the certificate of
    tile i (its serial parts would leave a core idle) runs while tile i + 1 is labelled:
    each certification waits (5 s at most) until the next tile's labelling has started. It
    runs off the main thread, which only waits for tiles, as without the overlap. The arrays
    are the sequential sweep's."""
    from atlas.kernels.threads import threadsafe_layer

    if not threadsafe_layer():
        pytest.skip("workqueue threading layer: tiles are labelled and certified together")
    started, overlaps, off_main = {}, [], []
    labelling, certify = schedule.label_tile, schedule.certify_tile

    def labelling_spy(point, x0, v0, rows, *args, **kwargs):
        started.setdefault(rows.start // 2, threading.Event()).set()
        return labelling(point, x0, v0, rows, *args, **kwargs)

    def certify_spy(point, rows, res, **kwargs):
        index = rows.start // 2
        off_main.append(threading.current_thread() is not threading.main_thread())
        if index + 1 < 8:
            overlaps.append(started.setdefault(index + 1, threading.Event()).wait(5.0))
        return certify(point, rows, res, **kwargs)

    monkeypatch.setattr(schedule, "label_tile", labelling_spy)
    monkeypatch.setattr(schedule, "certify_tile", certify_spy)
    got = _arrays(atlas.run(_config(tmp_path), quiet=True))
    for name in VARIABLES:
        np.testing.assert_array_equal(got[name], reference[name], err_msg=name)
    assert overlaps == [True] * 7 and off_main == [True] * 8


@pytest.mark.slow
def test_a_failure_of_the_tile_ahead_comes_after_the_tile_being_written(tmp_path,
                                                                        monkeypatch):
    """Tile 3 fails while tile 2 is being written: tile 2 is kept, then the caller gets
    tile 3's own exception."""
    failed = threading.Event()
    compute, write = schedule.label_tile, TileStore.write

    def computing(point, x0, v0, rows, *args, **kwargs):
        if rows.start // 2 == 3:
            failed.set()
            raise ValueError("tile 3: no such orbit")
        return compute(point, x0, v0, rows, *args, **kwargs)

    def writing(self, index, *args):
        if index == 2:
            assert failed.wait(5.0)
        write(self, index, *args)

    monkeypatch.setattr(schedule, "label_tile", computing)
    monkeypatch.setattr(TileStore, "write", writing)
    cfg = _config(tmp_path)
    with pytest.raises(ValueError, match="^tile 3: no such orbit$"):
        atlas.run(cfg, quiet=True)
    partial = cfg.output.with_name(cfg.output.name + ".partial")
    assert describe(partial)["tiles_done"] == 3
    assert TileStore.read(partial).done().tolist() == [0, 1, 2]


@pytest.mark.slow
def test_a_failed_write_abandons_the_tile_ahead_and_the_run_resumes(tmp_path, monkeypatch,
                                                                    reference):
    """The write of tile 1 fails while tile 2 computes: the run raises at once (it does not
    wait for tile 2), tile 0 is kept, and the next run finishes the atlas unchanged."""
    release, state = threading.Event(), {}
    compute, write = schedule.label_tile, TileStore.write

    def computing(point, x0, v0, rows, *args, **kwargs):
        if rows.start // 2 == 2:
            release.wait(10.0)
            state["tile 2 finished"] = True
        return compute(point, x0, v0, rows, *args, **kwargs)

    def writing(self, index, *args):
        if index == 1:
            raise OSError(28, "No space left on device")
        write(self, index, *args)

    cfg = _config(tmp_path)
    with monkeypatch.context() as m:
        m.setattr(schedule, "label_tile", computing)
        m.setattr(TileStore, "write", writing)
        with pytest.raises(StorageError, match="No space left on device"):
            atlas.run(cfg, quiet=True)
        assert "tile 2 finished" not in state  # abandoned, not waited for
        release.set()
    partial = cfg.output.with_name(cfg.output.name + ".partial")
    assert TileStore.read(partial).done().tolist() == [0]
    got = _arrays(atlas.run(cfg, quiet=True))
    for name in VARIABLES:
        np.testing.assert_array_equal(got[name], reference[name], err_msg=name)


SWEEP_CUDA = r"""
import json
import numpy as np
import atlas
from atlas.pipeline import schedule, sweep
from atlas.kernels.cuda import cuda_status
assert cuda_status() == (True, "CUDA simulator"), cuda_status()
from numba import cuda

made = []
real = cuda.pinned_array
cuda.pinned_array = lambda *a, **k: made.append(1) or real(*a, **k)
cfg = atlas.load_config({config!r})
got = atlas.run(cfg, quiet=True).to_dataset(inherit=False)
pinned = len(made)

def sequential(cfg, tiles, points, todo, device):
    for index in todo:
        yield index, schedule.compute_tile(*schedule.tile_args(cfg, tiles.layout, points,
                                                               index), backend=device)

schedule.SCHEDULERS["local"] = schedule.Scheduler(sequential, lambda tiles: False)
ref = atlas.run(cfg.model_copy(update={{"output": cfg.output.with_name("seq.h5")}}),
                quiet=True).to_dataset(inherit=False)
print(json.dumps({{"pinned": pinned, "tiles": int(sweep.layout_of(cfg).n_tiles),
                  "same": [bool(np.array_equal(got[n].values, ref[n].values, equal_nan=True))
                           for n in ("attractor", "status", "t_trap", "boundary_distance")]}}))
"""


@pytest.mark.slow
def test_a_cuda_sweep_looks_ahead_on_pooled_buffers(tmp_path):
    """The CUDA backend in the sweep (simulator): tiles labelled from the background thread
    on one set of pooled buffers give the sequential sweep's arrays."""
    cfg = write_config(tmp_path / "gpu.yaml", """\
grid:
  theta0: {start: -3pi, stop: 3pi, num: 8}
  theta_dot0: {start: -4, stop: 4, num: 6}
integrator: {dt: 0.01, t_max: 5}
separatrices: {enabled: false}
execution: {tile_orbits: 16, backend: cuda}
output: %s
""" % (tmp_path / "gpu.h5"))
    out = _child(SWEEP_CUDA.format(config=str(cfg)), simulator=True)
    assert out["same"] == [True] * 4
    assert out["tiles"] == 3 and out["pinned"] == 5  # one set, made for the first tile


def test_gpu_tiles_default_to_filling_the_device():
    """Without ``execution.tile_orbits`` a GPU tile is TILE_ORBITS_CUDA orbits (several waves
    of the device), a CPU tile TILE_ORBITS; a configured size holds on both."""
    from atlas import defaults
    from atlas.pipeline.config import Config
    from atlas.pipeline.sweep import layout_of

    grid = {"theta0": {"start": -3.0, "stop": 3.0, "num": 4096},
            "theta_dot0": {"start": -4.0, "stop": 4.0, "num": 4096}}
    cfg = Config.model_validate({"grid": grid})
    assert layout_of(cfg).rows_per_tile == defaults.TILE_ORBITS // 4096
    assert layout_of(cfg, "cuda").rows_per_tile == defaults.TILE_ORBITS_CUDA // 4096
    assert layout_of(cfg.model_copy(update={"execution": cfg.execution.model_copy(
        update={"backend": "cuda"})})).rows_per_tile == defaults.TILE_ORBITS_CUDA // 4096
    sized = Config.model_validate({"grid": grid, "execution": {"tile_orbits": 8192}})
    assert layout_of(sized, "cuda").rows_per_tile == layout_of(sized).rows_per_tile == 2
