"""Convergence studies: grids of backbone runs, frequency tables and observed rates.

A study runs :func:`mmshbm.backbone` over a grid — harmonics × elements × method × any
model parameter (a beam field such as ``gap`` or ``E``, the mesh ``grading``) or solver
option — and collects the branches in a :class:`Study`. :meth:`Study.table` tabulates
the frequency at chosen amplitudes, :meth:`Study.convergence` fits observed convergence
rates in H and in the number of elements.

The reference of a convergence fit is the finest run of its series (largest H, or most
elements), not the exact solution: the rates say how fast the runs approach the finest
one, and a rate fitted on two points is a two-point slope. Compare with
:mod:`mmshbm.methods.exact` for errors against the truth.

Runs go through any :class:`concurrent.futures.Executor`: a local process pool by
default, in-process when ``executor`` is None or ``"serial"``, or a Dask cluster's
executor (``dask.distributed.Client.get_executor()``, or ``executor="dask"`` for a local
cluster). Workers receive only picklable run descriptions (:class:`RunSpec`: beam data or
model file or matrices, H, method, options) and return branches without their solver;
the solver is rebuilt on the parent side when a per-point method needs it.
"""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import _validate as check
from .._warnings import BranchWarning
from ..results.base import versions
from ..results.branch import (
    Branch,
    branch_from_payload,
    branch_payload,
    read_archive,
    write_archive,
)
from .convergence import ConvergenceFit, format_convergence
from .executors import run_specs
from .runspec import RunSpec, build_model, execute
from .study_grid import _AXES, _unit, grid_specs, monte_carlo
from .table_rows import replay, row_values
from .tables import (
    FrequencyTable,
    findings_count,
    findings_table,
    format_cells,
    run_details,
    series_note,
    summarize,
)

__all__ = ["run_study", "figure2_study", "monte_carlo", "Study", "RunSpec", "FrequencyTable",
           "ConvergenceFit", "STUDY_FORMAT", "execute", "build_model"]

log = logging.getLogger(__name__)

STUDY_FORMAT = "mmshbm.Study"
FORMAT_VERSION = 1
#: grid coordinates that are not parameters


# ---------------------------------------------------------------------- study
@dataclass(eq=False)
class Study:
    """The branches of a grid of runs.

    Attributes
    ----------
    runs : list of dict
        Grid coordinates of each run (``method``, ``elements`` for beams, ``harmonics``,
        and every varied parameter).
    branches : list of Branch
        One per run, same order; solvers are rebuilt on demand.
    metadata : dict
        Grid definition, executor, wall time (s), versions.
    """

    runs: list
    branches: list
    metadata: dict = field(default_factory=dict)
    # tables already computed: (amplitudes, unit, branch ids) -> FrequencyTable
    _tables: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    # rows computed by the workers: (amplitudes, unit) -> {run index: TableRow}
    _rows: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.runs)

    def __iter__(self) -> Iterator[tuple[dict, Branch]]:
        return iter(zip(self.runs, self.branches, strict=True))

    def select(self, **coords) -> list[tuple[dict, Branch]]:
        """The (coordinates, branch) pairs whose coordinates match all of ``coords``."""
        return [(r, b) for r, b in self if all(r.get(k) == v for k, v in coords.items())]

    def branch(self, **coords) -> Branch:
        """The one branch matching ``coords`` (e.g. ``harmonics=5, elements=21``).

        Raises
        ------
        KeyError
            If no run or several runs match.
        """
        found = self.select(**coords)
        if len(found) != 1:
            raise KeyError(f"{len(found)} runs match {coords}; coordinates are {self.axes}")
        return found[0][1]

    @property
    def axes(self) -> list[str]:
        """Names of the grid coordinates, in table order."""
        names = [a for a in _AXES if any(a in r for r in self.runs)]
        return names + [k for k in (self.runs[0] if self.runs else {}) if k not in names]

    # ------------------------------------------------------------------ tables
    def table(self, amplitudes, unit: str = "gap") -> FrequencyTable:
        """Frequency (Hz) of every run at ``amplitudes``, with notes.

        Parameters
        ----------
        amplitudes : sequence of float, shape (n_amplitudes,)
            Tip amplitudes, in m (``unit="m"``) or in multiples of each run's gap.
        unit : {"gap", "m"}

        Returns
        -------
        FrequencyTable
            ``frequency`` has shape (n_runs, n_amplitudes): the point solved at that
            amplitude on the branch's family front (:meth:`Branch.frequency_at`); NaN where
            the front does not reach it or skips it. ``notes`` says why for every NaN (the
            internal resonance whose tongue was skipped, or why the run stopped) and
            cautions values next to a jump of the family (:mod:`mmshbm.analysis.skips`);
            ``mode_share`` is the starting mode's share of the kinetic energy there and
            ``partner`` the strongest other mode (k, j, share).
        """
        amps = _amplitudes(amplitudes)
        unit = _unit(unit)
        # the report, the CSV and the convergence plot ask for the same table: solved once
        key = (tuple(amps.tolist()), unit, tuple(map(id, self.branches)), tuple(map(id, self.runs)))
        if key in self._tables:
            return self._tables[key]
        # rows the workers computed after their runs (run_study(tabulate=...)), used once
        done = self._rows.pop(key[:2], {})
        n = len(self)
        f = np.full((n, len(amps)), np.nan)
        share = np.full((n, len(amps)), np.nan)
        notes, partner = [], []
        for i, b in enumerate(self.branches):
            row = done.get(i)
            if row is not None:
                replay(row, b)
                values = row.frequency, row.mode_share, row.partner, row.notes
            else:
                values = row_values(b, amps, unit)
            f[i], share[i] = values[0], values[1]
            partner.append(list(values[2]))
            notes.append(list(values[3]))
        table = FrequencyTable(axes=self.axes, runs=[dict(r) for r in self.runs], amplitudes=amps, unit=unit,
                               frequency=f, status=[b.status for b in self.branches], notes=notes,
                               mode_share=share, partner=partner)
        self._tables[key] = table
        return table

    def convergence(self, amplitudes, unit: str = "gap", *, table: FrequencyTable | None = None
                    ) -> list[ConvergenceFit]:
        """Observed convergence in H and in the number of elements.

        For every series of runs that differ only in ``harmonics`` (or only in
        ``elements``) and every amplitude: the successive differences, the local orders of
        three consecutive runs, a rate only where the two finest local orders agree, and
        the spread of the three finest runs (:mod:`mmshbm.analysis.convergence`). No
        exact solution is assumed; compare with :mod:`mmshbm.methods.exact` for errors
        against the truth.

        Parameters
        ----------
        table : FrequencyTable, optional
            :meth:`table` of the same amplitudes, if already computed.

        Returns
        -------
        list of ConvergenceFit
        """
        table = self.table(amplitudes, unit) if table is None else table
        fits = []
        for vary in ("harmonics", "elements"):
            others = [a for a in self.axes if a != vary]
            groups: dict[tuple, list[int]] = {}
            for i, r in enumerate(self.runs):
                if vary in r:
                    groups.setdefault(tuple(_hashable(r.get(a)) for a in others), []).append(i)
            for idx in groups.values():
                values = np.array([self.runs[i][vary] for i in idx], dtype=float)
                if len(set(values)) < 2 or len(set(values)) < len(values):
                    continue
                order = np.argsort(values)
                idx = [idx[j] for j in order]
                values = values[order]
                fixed = {a: self.runs[idx[0]].get(a) for a in others if a in self.runs[idx[0]]}
                for j, amp in enumerate(table.amplitudes):
                    fit = ConvergenceFit.fit(vary, fixed, float(amp), table.unit, values,
                                             table.frequency[idx, j])
                    fit.note = series_note(vary, [self.runs[i] for i in idx], table.frequency[idx, j],
                                            [table.notes[i][j] for i in idx])
                    fits.append(fit)
        return fits

    def report(self, amplitudes, unit: str = "gap") -> str:
        """Text: the frequency table (with the reason for every empty cell), elements × H
        matrices, convergence, what each run met (jumps, skipped intervals, resonances),
        the summary, every finding and warning of every run, and the study's wall time
        (the CLI writes it to the study's ``*_table.txt``)."""
        table = self.table(amplitudes, unit)
        parts = [table.to_text()]
        if {"harmonics", "elements"} <= set(self.axes):
            pivot = table.pivot_text()
            if pivot:
                parts.append(pivot)
        fits = self.convergence(amplitudes, unit, table=table)
        if fits:
            parts.append(format_convergence(fits))
        if any(b.records.get("on_family") is not None for b in self.branches):
            parts.append(format_cells(self.runs, self.branches, self.axes))
        parts.append(self.summary())
        details = run_details(self.runs, self.branches)
        if details:
            parts.append(details)
        elapsed = self.metadata.get("elapsed_s")
        if elapsed is not None:
            text = f"wall time: {len(self)} runs in {elapsed:.1f} s, {self.metadata.get('executor', '?')}"
            if self.metadata.get("tasks") and self.metadata.get("executor") != "serial":
                text += f", {self.metadata['tasks']} tasks of up to {self.metadata['chunksize']} runs"
            parts.append(text)
        return "\n\n".join(parts)

    def to_csv(self, path, amplitudes, unit: str = "gap") -> Path:
        """Write :meth:`table` to ``path`` (CSV)."""
        return self.table(amplitudes, unit).to_csv(path)

    # ------------------------------------------------------------------ files
    def save(self, path) -> Path:
        """Write the study to one ``.npz`` archive: every branch's arrays (keys
        ``run<i>__<name>``) and a JSON ``metadata`` record with the runs' coordinates,
        each branch's metadata (enough to redo it) and the study's metadata."""
        arrays, records = {}, []
        for i, b in enumerate(self.branches):
            a, m = branch_payload(b, prefix=f"run{i}__")
            arrays.update(a)
            records.append(m)
        meta = {"format": STUDY_FORMAT, "format_version": FORMAT_VERSION, "runs": self.runs,
                "branches": records, "metadata": self.metadata, "saved_with": versions()}
        return write_archive(path, arrays, meta)

    @classmethod
    def load(cls, path, attach_solver: bool = False) -> Study:
        """Read a study written by :meth:`save` (solvers rebuilt now if ``attach_solver``,
        otherwise on demand)."""
        arrays, meta = read_archive(path)
        if meta.get("format") != STUDY_FORMAT:
            raise ValueError(f"{str(path)!r} is not a saved mmshbm Study (format {meta.get('format')!r})")
        try:
            runs, records = list(meta["runs"]), list(meta["branches"])
        except (KeyError, TypeError):
            raise ValueError(f"{str(path)!r}: malformed study record") from None
        branches = [branch_from_payload(arrays, m, prefix=f"run{i}__") for i, m in enumerate(records)]
        if attach_solver:
            for b in branches:
                b.attach_solver()
        return cls(runs=runs, branches=branches, metadata=dict(meta.get("metadata", {})))

    def summary(self) -> str:
        """Text: runs that reached their bounds, those that did not and why, and findings."""
        return summarize(self.runs, self.branches)

    def findings(self) -> str:
        """Text: one row per run (status, family, truncation effects, skipped intervals,
        other warnings: :func:`~mmshbm.analysis.tables.findings_table`) and a line of
        counts; every message in :meth:`report`."""
        return "\n".join([findings_table(self.runs, self.branches, _varying(self.runs)),
                          findings_count(self.runs, self.branches)])

    def __repr__(self) -> str:
        done = sum(b.completed for b in self.branches)
        return f"Study({len(self)} runs over {self.axes}, {done} completed, {len(self) - done} incomplete)"


# ---------------------------------------------------------------------- running
def run_study(beam=None, *, model=None, harmonics: Sequence[int] = (1, 3, 5),
              elements: Sequence[int] | None = None, methods: Sequence[str] = ("mmshbm",),
              params: Mapping[str, Sequence] | None = None, samples: Mapping[str, Sequence] | None = None,
              grading: float = 10.0, max_amplitude: float | None = None, unit: str = "m",
              executor="process", workers: int = 2, chunksize="auto", verbose: bool = False,
              warn: bool = True, tabulate: tuple | None = None, while_running=None, **options) -> Study:
    """Run :func:`mmshbm.backbone` over a grid and collect the branches.

    Parameters
    ----------
    beam : TimoshenkoBeam, optional
        The beam (default :func:`mmshbm.default_beam`); not with ``model``.
    model : Model or path, optional
        A user model instead of a beam: a :class:`~mmshbm.model.Model` (its matrices are
        sent to the workers) or a ``.npz`` file of :meth:`Model.save_npz` (its path is
        sent). ``elements`` does not apply; ``params`` may vary ``gap`` only.
    harmonics : sequence of int
        Values of H.
    elements : sequence of int, optional
        Element counts of the beam (default (8, 21)).
    methods : sequence of str
        Methods of :func:`mmshbm.backbone`.
    params : mapping of str to sequence, optional
        Further grid axes: beam fields (``gap`` (m), ``E`` (Pa), ``rho`` (kg/m³), ...),
        ``grading``, or any option of :func:`mmshbm.backbone` (e.g. ``n_samples``,
        ``penalty_stiffness``).
    samples : mapping of str to sequence, optional
        Parameters varied *together* (a Monte-Carlo or any list of parameter sets): equal
        lengths n, one run per index i with every name at its i-th value (coordinates
        ``sample`` = i and the names), crossed with the rest of the grid. Same names as
        ``params`` allows, none in both. :func:`monte_carlo` draws such samples.
    grading : float
        Mesh grading of the beam (when not varied).
    max_amplitude : float, optional
        Largest amplitude per run, in m (``unit="m"``) or gaps (``unit="gap"``); default
        10 gaps.
    unit : {"m", "gap"}
        Unit of ``max_amplitude``.
    executor : "process", "serial", None, "dask", concurrent.futures.Executor or dask Client
        Where the runs go: a local process pool of ``workers`` processes (default), this
        process (None / "serial"), a local Dask cluster ("dask"), or any executor
        (e.g. ``client.get_executor()``; not shut down here).
    workers : int
        Processes of the pool or local Dask cluster.
    chunksize : int or "auto"
        Runs per task sent to the executor (:func:`mmshbm.analysis.executors.auto_chunksize`:
        one for small studies, about 16 tasks per worker for large ones), so that the
        per-task cost of the executor is paid per chunk; the numbers do not depend on it.
    verbose : bool
        Progress on stderr (a tqdm bar on a terminal, plain lines in a pipe or log).
    warn : bool
        Issue one :class:`~mmshbm.BranchWarning` summarising what the checks of the runs
        found (counts; :meth:`Study.findings` gives a row per run, :meth:`Study.report`
        every message), rather than a warning per finding.
    tabulate : (amplitudes, unit), optional
        The :meth:`Study.table` that will be asked for: each worker computes its runs'
        rows right after them (:mod:`mmshbm.analysis.table_rows`), instead of this
        process rebuilding every run's solver once all have finished; the table and its
        warnings are the same (they are issued when :meth:`Study.table` is called; log
        messages go where the workers' logging sends them, as their runs' do). Any other
        table, and the table of a user ``model``, is computed here as usual.
    while_running : callable, optional
        Called without arguments in this process once the runs are sent to the workers,
        so that work of the caller's overlaps them (the ``mmshbm study`` command imports
        matplotlib there).
    **options
        Passed to every :func:`mmshbm.backbone` call (continuation and method options).
        With ``tol`` (and ``max_harmonics``), every run chooses its H per point to meet
        it, and ``harmonics`` is the H each run starts from
        (:mod:`mmshbm.analysis.study_tolerance`: the H of each table cell, the mesh
        error at the table's amplitudes).

    Returns
    -------
    Study
        Runs in grid order (method, elements, harmonics, then ``params`` in the given
        order), whatever order they finished in.

    Raises
    ------
    ValueError, TypeError
        For a bad grid, executor or option; a run's own input error is re-raised.
    """
    specs = grid_specs(beam, model=model, harmonics=harmonics, elements=elements, methods=methods,
                       params=params, samples=samples, grading=grading, max_amplitude=max_amplitude,
                       unit=unit, **options)
    workers = check.integer("workers", workers, minimum=1)
    if model is not None:  # the table of a user model is solved on the parent's models (_parent_models)
        tabulate = None
    if tabulate is not None:
        amps, table_unit = tabulate
        tabulate = (tuple(_amplitudes(amps).tolist()), _unit(table_unit))
    t0 = time.perf_counter()
    branches, kind, info = run_specs(specs, executor, workers, chunksize=chunksize, verbose=verbose,
                                     tabulate=tabulate, while_running=while_running)
    elapsed = time.perf_counter() - t0
    rows = info.pop("rows", None)
    parent_models = _parent_models(model, specs)
    for spec, branch in zip(specs, branches, strict=True):
        if parent_models is not None:
            branch.model = parent_models[spec.index]
    grid = {"harmonics": [int(h) for h in harmonics], "methods": list(methods),
            "params": {k: list(v) for k, v in dict(params or {}).items()}, "options": options,
            "samples": {k: list(v) for k, v in dict(samples or {}).items()},
            "max_amplitude": max_amplitude, "unit": unit}
    if model is None:
        grid["elements"] = [int(n) for n in (elements or (8, 21))]
        grid["grading"] = grading
    log.info("study: %d runs in %.2f s (%s)", len(specs), elapsed, kind)
    study = Study(runs=[dict(s.coords) for s in specs], branches=branches,
                  metadata={"grid": grid, "executor": kind, "workers": workers, "elapsed_s": elapsed, **info,
                            "model_file": str(model) if isinstance(model, str | Path) else None})
    if rows is not None:
        study._rows[tabulate] = {i: row for i, row in enumerate(rows) if row is not None}
    if warn:
        flagged = sum(bool(b.findings or b.metadata.get("run_warnings")) for b in branches)
        if flagged:
            warnings.warn(f"study: {findings_count(study.runs, branches)}; study.findings() gives a row per "
                          "run, study.report(...) every message", BranchWarning, stacklevel=2)
    return study


def figure2_study(beam=None, harmonics=(1, 3, 5), elements=(8, 21), executor="process", workers: int = 2,
                  verbose: bool = False, **options) -> Study:
    """The runs of Figure 2 of Part I of the paper: H in {1, 3, 5} × {8, 21} elements, MMS-HBM,
    up to 10 gaps (see :func:`mmshbm.plotting.plot_figure2`)."""
    return run_study(beam, harmonics=harmonics, elements=elements, executor=executor, workers=workers,
                     verbose=verbose, **options)


def _varying(runs: list[dict]) -> list[str]:
    """The coordinates whose value differs between runs (all of the first run's when none)."""
    keys = list(dict.fromkeys(k for r in runs for k in r))
    varying = [k for k in keys if len({repr(r.get(k)) for r in runs}) > 1] or keys
    first = [k for k in ("harmonics", "elements") if k in varying]  # "H5, 21 el.", as the plots name runs
    return first + [k for k in varying if k not in first]


def _parent_models(model, specs: list[RunSpec]):
    """For user models: the Model of each run on the parent side (so that saved files
    carry the matrices); None for beams (their description rebuilds them)."""
    if model is None:
        return None
    cache: dict = {}
    out = {}
    for s in specs:
        key = s.source.get("gap")
        if key not in cache:
            cache[key] = build_model(s.source)
        out[s.index] = cache[key]
    return out


def _amplitudes(amplitudes) -> np.ndarray:
    amps = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    if amps.ndim != 1 or len(amps) == 0 or not np.all(np.isfinite(amps)) or np.any(amps <= 0):
        raise ValueError(f"amplitudes must be positive finite numbers, got {amplitudes!r}")
    return amps


def _hashable(v):
    return tuple(v) if isinstance(v, list) else v
