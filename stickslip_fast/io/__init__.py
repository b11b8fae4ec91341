"""The HDF5 result file: schema, writer and reader (the one place that knows the layout).

A sweep file is a plain HDF5 file that also reads as a netCDF-4 style labelled
dataset (``xarray.open_dataset(path, engine="h5netcdf")``). Layout (schema 1),
for a sweep of parameter(s) ``P1[, P2]`` with ``n1[, n2]`` values::

    /P1            (n1,)   coordinate: values of the first parameter
    /P2            (n2,)   coordinate (2-D sweeps only)
    /branch        (2,)    "up", "down" (mode "continuation-both" only)
    /point         (K,)    0..K-1, K = max_points
    /state         (S,)    state names: x1, dx1, phi1, dphi1, ..., [vb]
    /points        (grid..., point, state)  Poincare points, time order, NaN-padded
    /t_points      (grid..., point)         their times
    /count         (grid...)   number of stored points
    /period        (grid...)   detected period (0: none)
    /status        (grid...)   int8 code; attrs flag_values / flag_meanings
    /n_steps, /n_rejected, /n_crossings (grid...)
    /final_state   (grid..., state)
    /done          (grid...)   1 once the value is written (for resume)

Optional analysis datasets (only when the sweep was asked for them with
``sweep(..., analyses=...)``; the list is part of the configuration and its hash)::

    /sync_error    (grid...)   f8  analyses=("sync",): mean distance between disk i's
                               and disk 1's (x, dx, phi, dphi) over the stored
                               Poincare points (analysis.sync_error; 0 for N = 1,
                               NaN where there are no points)
    /lyapunov      (grid...)   f8  analyses=("lyapunov",): largest Lyapunov exponent,
                               plain Benettin average (analysis.largest_lyapunov
                               with the sweep's t_end, t_transient, rtol, atol and
                               the value's own initial state)
    /lyapunov_fit  (grid...)   f8  the same run's least-squares slope estimate

``grid`` is ``[branch,] P1[, P2]``. Root attributes: ``schema_version``,
``package_version``, ``config`` (JSON of everything that determines the
results), ``config_sha256``, ``created``, ``title``, ``notes`` and a flat copy of
the main settings for quick inspection. The full description for collaborators
is docs/file-format.md.

Trajectory file (schema 1, root attribute ``kind = "trajectory"``), one run of
:func:`stickslip_fast.simulate`, written by :func:`write_trajectory`::

    /t             (t,)              coordinate: sample times (empty without sample_dt)
    /state         (state,)          state names x1, dx1, phi1, dphi1, ..., [vb]
    /y             (t, state)        samples on the uniform grid t_transient + k sample_dt
    /crossing      (crossing,)       0..k-1
    /t_poincare    (crossing,)       times of the Poincare points (local minima of x1)
    /poincare      (crossing, state) full state at those times
    /final_state   (state,)          state at t_end

Root attributes: ``schema_version``, ``package_version``, ``kind``, ``config``
(JSON: system, settings, y0, sample_dt and the TOML mapping it came from),
``config_sha256``, ``created``, ``title``, ``notes``, ``status``, ``period``,
``n_steps``, ``n_rejected``, ``n_crossings``, ``t_final``, ``amplitude``,
``rest_time`` (time at rest at the end, -1 if moving; files of 0.1.0 lack it),
``method``. Like a sweep file it opens with
``xarray.open_dataset(path, engine="h5netcdf")``.
"""

# The schema and writers live in the modules of this package: base (bounded
# opens, digests, disk room, the writer lock), layout (the per-value datasets),
# sweepfile, verify, readers, trajectory, census. The public names are re-exported here.
from .base import (  # noqa: F401 (the private helpers stay in io.base)
    SWMR_READ_ATTEMPTS,
    ConfigMismatchError,
    DiskFullError,
    ResultFileError,
    _make_parent,
    config_digest,
    disk_full,
    ensure_room,
    open_h5,
    writer_alive,
)
from .basins import read_basins_meta, write_basins  # noqa: F401
from .basins_extras import read_basins_extras, store_extra  # noqa: F401
from .branchfile import read_branch, write_branch  # noqa: F401
from .census import (  # noqa: F401
    CENSUS_RUN_FIELDS,
    CensusFile,
    CensusLayout,
    read_census,
    write_census_classification,
)
from .layout import (  # noqa: F401
    _DESCRIPTIONS,
    ANALYSES,
    ANALYSIS_FIELDS,
    PER_VALUE_FIELDS,
    SCHEMA_VERSION,
    MemoryStore,
    SweepLayout,
)
from .readers import (  # noqa: F401
    file_kind,
    read_dataset,
    read_root_attrs,
    read_sweep,
    sweep_summary,
    verify_sweep,
)
from .sweepfile import (  # noqa: F401
    SweepFile,
    _new_file,
    _rebuild,
)
from .trajectory import (  # noqa: F401
    _jsonable,
    read_trajectory,
    read_trajectory_header,
    write_trajectory,
)
from .verify import _data_fields, scan_sweep, stored_config  # noqa: F401

__all__ = [
    "SCHEMA_VERSION",
    "ConfigMismatchError",
    "ResultFileError",
    "DiskFullError",
    "open_h5",
    "SweepLayout",
    "MemoryStore",
    "read_dataset",
    "sweep_summary",
    "verify_sweep",
    "file_kind",
    "SweepFile",
    "config_digest",
    "read_sweep",
    "PER_VALUE_FIELDS",
    "ANALYSES",
    "ANALYSIS_FIELDS",
    "write_trajectory",
    "read_trajectory",
    "read_trajectory_header",
    "CensusLayout",
    "CensusFile",
    "read_census",
    "write_census_classification",
]

from ..base.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__)  # submodules as attributes on first use
