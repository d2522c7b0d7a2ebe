"""What a run is: its identity (what decides its tiles, so that only an equal run may continue
a partial one), the identity's hash, and the provenance attributes of the file it writes.
"""

from __future__ import annotations

import hashlib
import json
import sys
from datetime import datetime, timezone

import numpy as np
import xarray as xr

from atlas import lazy_dask  # noqa: F401 (installs itself)
from atlas.defaults import BACKEND_WORDS
from atlas.kernels import source_hash
from atlas.labels.trap import CHECK_EVERY
from atlas.models.registry import DEFAULT as DEFAULT_MODEL
from atlas.pipeline.config import Config, config_hash, integrator_json
from atlas.store.schema import FORMAT_VERSION

__all__ = ["run_identity", "identity_hash", "file_attrs", "library_versions"]


def run_identity(cfg: Config, backend: str) -> dict:
    """What determines a run's tiles, so a partial run may be continued only by an equal one:
    the grid, the physics (every key of the model's section: ``pendulum`` for the pendulum),
    the integrator, the kernels' trap-check interval, the atlas version and a digest of the
    kernels' sources (:func:`atlas.kernels.source_hash`: a kernel or a decision rule that
    changed within one version changes the labels, and its tiles must not mix with the
    earlier ones), the kernel class that computes the labels ('cuda' for the GPU kernels;
    'cpu' for the CPU kernels, which the Dask backend runs too), and the separatrix settings
    when they are enabled (they measure d_cert, which decides each tile's certified
    statuses). Not the tiling, the output path or the name."""
    from atlas import __version__

    return {"grid": cfg.grid.model_dump(mode="json"),
            cfg.description.section: cfg.section.model_dump(mode="json"),
            "integrator": integrator_json(cfg.integrator),
            "separatrices": (cfg.separatrices.model_dump(mode="json")
                             if cfg.separatrices.enabled and cfg.description.name == DEFAULT_MODEL
                             else {"enabled": False}),  # the pendulum's section
            "check_every": int(CHECK_EVERY), "atlas_version": __version__,
            "kernel_sources": source_hash(), "kernels": BACKEND_WORDS[backend][0]}


def identity_hash(identity: dict) -> str:
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()[:16]


def library_versions() -> dict:
    """The versions of atlas, Python and the libraries that computed and wrote the file (as
    their distributions report them: no import of the file libraries here)."""
    from importlib.metadata import version

    from atlas import __version__

    return {"atlas_version": __version__, "numpy_version": np.__version__,
            "numba_version": version("numba"), "xarray_version": xr.__version__,
            "h5py_version": version("h5py"), "h5netcdf_version": version("h5netcdf"),
            "python_version": sys.version.split()[0]}


def file_attrs(cfg: Config, identity: dict) -> dict:
    attrs = {
        "title": f"atlas basin map: {cfg.name}",
        "model": cfg.description.name,
        "Conventions": "CF-1.10",
        "format_version": np.int64(FORMAT_VERSION),
        "method": cfg.integrator.method,
        "dt": cfg.integrator.dt,
        "t_max": cfg.integrator.t_max,
        "check_every": np.int64(CHECK_EVERY),
        "config": cfg.to_json(),
        "config_hash": config_hash(cfg),
        "run_identity": identity_hash(identity),
        "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        **library_versions(),
    }
    return attrs
