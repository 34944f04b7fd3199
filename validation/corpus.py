"""A corpus of random models: how the defaults fare on structures that are not the beam.

:func:`generate` draws models from a seed, each one reproducible from its case alone
(:class:`CorpusCase`): chains of 1–7 masses ending in a massless contact node, trees
(branched spring–mass systems, a massless contact node hanging from one mass), and
clamped Timoshenko beams with random length, section, material, mesh and grading. Masses
and springs span four decades, gaps five; each model gets a one-sided stop, a clearance
(two stops on the contact node, the amplitude then measured at a DOF with mass), or
several contacts (two contact nodes, one-sided stops). H is drawn from {1, 3, 5, 9, 15}.

:func:`run_case` runs the default backbone to 10 gaps under a wall-clock limit and says
whether it reached its bound on the first mode's family; :func:`run_corpus` runs many
and :func:`summary` tabulates them (``python -m validation corpus N``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import signal
import threading
import time
import warnings
from collections.abc import Iterable

import numpy as np

__all__ = ["CSV_COLUMNS", "EXCEPTION", "CaseResult", "CorpusCase", "csv_row", "generate", "run_case",
           "run_corpus", "summary"]

KINDS = ("chain", "tree", "beam")
CONTACTS = ("one-sided", "clearance", "several")
HARMONICS = (1, 3, 5, 9, 15)


@dataclasses.dataclass(frozen=True)
class CorpusCase:
    """One random model of the corpus and the harmonics it is run with.

    Attributes
    ----------
    index : int
        Position in the corpus.
    seed : int
        The corpus seed (the case's random stream is ``(seed, index)``).
    kind : {"chain", "tree", "beam"}
    contact : {"one-sided", "clearance", "several"}
    harmonics : int
    params : dict
        Everything :meth:`model` needs (masses, springs, parents, beam data, gaps, sides).
    """

    index: int
    seed: int
    kind: str
    contact: str
    harmonics: int
    params: dict

    def model(self):
        """The :class:`~mmshbm.Model` of this case."""
        p = self.params
        if self.kind == "beam":
            return _beam_model(p)
        return _spring_mass_model(p)

    @property
    def label(self) -> str:
        return f"#{self.index} {self.kind}/{self.contact} H={self.harmonics}"


def generate(n: int, seed: int = 0, kinds: Iterable[str] = KINDS, contacts: Iterable[str] = CONTACTS,
             harmonics: Iterable[int] = HARMONICS) -> list[CorpusCase]:
    """``n`` random cases; the same (n, seed, kinds, contacts, harmonics) give the same
    cases, and case i does not depend on n.

    Kinds are drawn with weights chain 0.5, tree 0.3, beam 0.2 (among those asked),
    contacts with one-sided 0.6, clearance 0.3, several 0.1 (beams: one-sided or
    clearance)."""
    kinds, contacts, harmonics = tuple(kinds), tuple(contacts), tuple(int(h) for h in harmonics)
    if n < 0 or not kinds or not contacts or not harmonics:
        raise ValueError("need n >= 0 and at least one kind, contact type and harmonic count")
    for k in kinds:
        if k not in KINDS:
            raise ValueError(f"unknown kind {k!r}; choose from {KINDS}")
    for c in contacts:
        if c not in CONTACTS:
            raise ValueError(f"unknown contact type {c!r}; choose from {CONTACTS}")
    return [_case(i, seed, kinds, contacts, harmonics) for i in range(n)]


def _pick(rng, options, weights):
    w = np.array([weights[o] for o in options], dtype=float)
    return options[int(rng.choice(len(options), p=w / w.sum()))]


def _case(i: int, seed: int, kinds, contacts, harmonics) -> CorpusCase:
    rng = np.random.default_rng([seed, i])
    kind = _pick(rng, kinds, {"chain": 0.5, "tree": 0.3, "beam": 0.2})
    allowed = tuple(c for c in contacts if kind != "beam" or c != "several") or contacts
    contact = _pick(rng, allowed, {"one-sided": 0.6, "clearance": 0.3, "several": 0.1})
    H = int(harmonics[int(rng.integers(len(harmonics)))])
    gap = float(10 ** rng.uniform(-5, 0))
    if kind == "beam":
        params = {"length": float(rng.uniform(0.2, 2.0)), "width": float(rng.uniform(0.01, 0.06)),
                  "height": float(rng.uniform(0.003, 0.04)), "E": float(rng.uniform(70e9, 210e9)),
                  "rho": float(rng.uniform(2700.0, 7850.0)), "elements": int(rng.integers(3, 31)),
                  "grading": float(10 ** rng.uniform(0, 1))}
    else:
        n_m = int(rng.integers(1, 8))
        masses = 10 ** rng.uniform(-2, 2, n_m)
        springs = 10 ** rng.uniform(1, 5, n_m)  # spring i joins mass i to its parent (ground for 0)
        parents = [-1] + ([int(rng.integers(0, m)) for m in range(1, n_m)] if kind == "tree"
                          else list(range(n_m - 1)))
        ground = [bool(rng.random() < 0.3) and m > 0 for m in range(n_m)] if kind == "tree" else [False] * n_m
        ground_k = 10 ** rng.uniform(1, 5, n_m)
        n_nodes = 2 if contact == "several" else 1
        hosts = [n_m - 1] if kind == "chain" else [int(rng.integers(n_m))]
        if n_nodes == 2:
            others = [m for m in range(n_m) if m != hosts[0]]
            hosts.append(int(rng.choice(others)) if others else hosts[0])
        node_k = 10 ** rng.uniform(1, 5, n_nodes) * (10 ** rng.uniform(0, 2, n_nodes))
        params = {"masses": masses.tolist(), "springs": springs.tolist(), "parents": parents,
                  "ground": ground, "ground_k": ground_k.tolist(), "hosts": hosts,
                  "node_k": node_k.tolist()}
    if contact == "clearance":
        lower = gap if rng.random() < 0.5 else float(gap * 10 ** rng.uniform(-0.5, 0.5))
        params.update(gaps=[gap, lower], sides=[1, -1])
    elif contact == "several":
        params.update(gaps=[gap, float(gap * 10 ** rng.uniform(-0.5, 0.5))],
                      sides=[int(rng.choice([1, -1])) for _ in range(2)])
    else:
        params.update(gaps=[gap], sides=[int(rng.choice([1, -1]))])
    return CorpusCase(i, int(seed), kind, contact, H, params)


def _spring_mass_model(p: dict):
    from mmshbm.model.model import Model

    masses, springs, parents = p["masses"], p["springs"], p["parents"]
    n_m = len(masses)
    hosts, node_k = p["hosts"], p["node_k"]
    n = n_m + len(hosts)
    K = np.zeros((n, n))

    def join(a, b, k):  # b = -1: ground
        K[a, a] += k
        if b >= 0:
            K[b, b] += k
            K[a, b] -= k
            K[b, a] -= k

    for m in range(n_m):
        join(m, parents[m], springs[m])
        if p["ground"][m]:
            join(m, -1, p["ground_k"][m])
    for c, (host, k) in enumerate(zip(hosts, node_k, strict=True)):
        join(n_m + c, host, k)
    M = np.diag(list(masses) + [0.0] * len(hosts))
    gaps, sides = p["gaps"], p["sides"]
    if len(hosts) == 1:
        dofs = [n_m] * len(gaps)
    else:
        dofs = [n_m, n_m + 1]
    return Model.from_matrices(M, K, dofs if len(dofs) > 1 else dofs[0], gaps if len(gaps) > 1 else gaps[0],
                               sides if len(sides) > 1 else sides[0], description={"kind": "corpus"})


def _beam_model(p: dict):
    from mmshbm.fe.beam import TimoshenkoBeam
    from mmshbm.model.model import Model

    beam = TimoshenkoBeam(p["length"], p["width"], p["height"], p["E"], p["rho"], gap=p["gaps"][0])
    model = beam.model(p["elements"], p["grading"])
    if len(p["gaps"]) == 1:
        return model if p["sides"][0] == 1 else Model.from_matrices(model.M, model.K, model.contact_dof,
                                                                    p["gaps"][0], -1)
    tip = model.contact_dof
    return Model.from_matrices(model.M, model.K, [tip, tip], p["gaps"], p["sides"],
                               description={"kind": "corpus-beam"})


#: the status kind of a case whose run raised (no Status kind: the branch never ended)
EXCEPTION = "exception"

#: the columns of corpus.csv, in order (:func:`csv_row`); new columns go at the end
CSV_COLUMNS = ("index", "seed", "kind", "contact", "harmonics", "completed", "status", "seconds", "points",
               "jumps", "frequency", "path_completed", "same_as_path", "cpu_seconds", "status_kind",
               "status_detail", "raised", "family_ended")


@dataclasses.dataclass
class CaseResult:
    """What one case gave.

    Attributes
    ----------
    case : CorpusCase
    completed : bool
        Reached the amplitude bound on the first mode's family.
    status : str
        The branch's status text, or ``"exception: <type>: <message>"`` (for display and
        the CSV; nothing is classified from it).
    seconds : float
    points, jumps : int
    frequency : float
        Frequency (Hz) at the last point (NaN if none).
    path_completed : bool or None
        With ``compare_path``: the plainly followed branch reached the bound without
        leaving the family (no tongue).
    same_as_path : bool or None
        With ``compare_path`` and ``path_completed``: the default ends where the plain
        branch ends (relative frequency difference below 1e-6).
    cpu_seconds : float
        Processor time of the default run (s): its duration on an idle core, where
        ``seconds`` (wall clock) grows with the load of a shared machine.
    status_kind : str
        The branch's :attr:`mmshbm.core.status.Status.kind` (``"bound"``,
        ``"family ended"``, ``"max_steps"``, ...), or :data:`EXCEPTION` when the run
        raised. :func:`run_case` sets it from the status value; left empty, it is the kind
        of ``Status.parse(status)`` (a status read back from corpus.csv's text).
    status_detail : str
        The status's detail (the bound's name, a failure's message, the exception's type
        and message): human text, for display only. Left empty with ``status_kind`` also
        empty, it is the detail of ``Status.parse(status)``.
    """

    case: CorpusCase
    completed: bool
    status: str
    seconds: float
    points: int = 0
    jumps: int = 0
    frequency: float = math.nan
    path_completed: bool | None = None
    same_as_path: bool | None = None
    cpu_seconds: float = math.nan
    status_kind: str = ""
    status_detail: str = ""

    def __post_init__(self):
        if not self.status_kind:
            from mmshbm.core.status import Status

            parsed = Status.parse(self.status)
            self.status_kind, self.status_detail = parsed.kind, self.status_detail or parsed.detail

    @property
    def raised(self) -> bool:
        """The run raised an exception (the case's status kind is :data:`EXCEPTION`)."""
        return self.status_kind == EXCEPTION

    @property
    def family_ended(self) -> bool:
        """The branch ended where the starting mode's family ends (status kind
        ``"family ended"``)."""
        from mmshbm.core.status import Status

        return self.status_kind == Status.FAMILY_ENDED

    @property
    def reason(self) -> str:
        """The failure's reason in a few words (empty when completed): the status kind,
        and a short piece of its detail for display."""
        from mmshbm.core.status import Status

        if self.completed:
            return ""
        if self.raised:
            return f"{EXCEPTION}: {self.status_detail}"[:80]
        if self.status_kind == Status.BOUND:
            if self.status_detail == "amplitude":
                return "bound off the family"
            return f"bound:{self.status_detail}"
        detail = self.status_detail.split(":", 1)[0].strip()[:40]
        return self.status_kind + (f": {detail}" if detail else "")


def csv_row(result: CaseResult) -> list:
    """The row of ``result`` in corpus.csv, one value per :data:`CSV_COLUMNS` entry."""
    r = result
    return [r.case.index, r.case.seed, r.case.kind, r.case.contact, r.case.harmonics, int(r.completed),
            str(r.status), f"{r.seconds:.4f}", r.points, r.jumps, repr(r.frequency), r.path_completed,
            r.same_as_path, f"{r.cpu_seconds:.4f}", r.status_kind, r.status_detail,
            int(r.raised), int(r.family_ended)]


class _TimeLimit(KeyboardInterrupt):
    """Raised from the continuation's callback when a case runs past its limit (the driver
    ends the branch with status "interrupted")."""


def _limited(seconds: float):
    """A continuation callback that interrupts a run after ``seconds`` of processor time
    (the run's own time, not the wall clock that a shared machine's load stretches)."""
    t0 = time.process_time()

    def callback(u, rec):
        if time.process_time() - t0 > seconds:
            raise _TimeLimit()

    return callback


@contextlib.contextmanager
def _hard_limit(seconds: float):
    """Interrupt whatever runs after ``seconds`` of the process's processor time (a
    profiling timer, SIGPROF): also inside a jump's pinned solves, which call no
    continuation callback. Only in the main thread of a process with ``setitimer``
    (elsewhere the callback alone limits the run, at its points)."""
    if not hasattr(signal, "setitimer") or threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise _TimeLimit()

    previous = signal.signal(signal.SIGPROF, interrupt)
    signal.setitimer(signal.ITIMER_PROF, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0.0)
        signal.signal(signal.SIGPROF, previous)


def run_case(case: CorpusCase, *, time_limit: float = 30.0, compare_path: bool = False,
             max_gaps: float = 10.0, options: dict | None = None) -> CaseResult:
    """Run the default backbone of ``case`` to ``max_gaps`` gaps (never raises: an
    exception is a result), with the further keyword arguments ``options`` of
    :func:`~mmshbm.backbone` (e.g. ``{"r": "residual"}``). A run past ``time_limit``
    seconds of processor time is interrupted at its next point (status "interrupted")."""
    from mmshbm.core.status import Status
    from mmshbm.methods.backbone import backbone

    t0, c0 = time.perf_counter(), time.process_time()
    try:
        model = case.model()
        with warnings.catch_warnings(), _hard_limit(time_limit):
            warnings.simplefilter("ignore")
            b = backbone(model, harmonics=case.harmonics, max_amplitude=max_gaps * model.gap,
                         callback=_limited(time_limit), **(options or {}))
    except _TimeLimit:  # outside the continuation (setup, the branch's checks)
        detail = f"past {time_limit:g} s of processor time"
        return CaseResult(case, False, str(Status(Status.INTERRUPTED, detail)), time.perf_counter() - t0,
                          cpu_seconds=time.process_time() - c0, status_kind=Status.INTERRUPTED,
                          status_detail=detail)
    except Exception as err:  # noqa: BLE001 - an exception is what the corpus counts
        detail = f"{type(err).__name__}: {err}"
        return CaseResult(case, False, f"{EXCEPTION}: {detail}", time.perf_counter() - t0,
                          cpu_seconds=time.process_time() - c0, status_kind=EXCEPTION, status_detail=detail)
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    status = Status.parse(b.status)
    on = b.records.get("on_family")
    completed = _at_amplitude_bound(status) and (on is None or (len(on) and on[-1] > 0.5))
    out = CaseResult(case, bool(completed), str(status), seconds, len(b),
                     sum(1 for s in b.special_points if s.kind == "jump"),
                     float(b.frequency[-1]) if len(b) else math.nan, cpu_seconds=cpu, status_kind=status.kind,
                     status_detail=status.detail)
    if compare_path:
        try:
            with warnings.catch_warnings(), _hard_limit(time_limit):
                warnings.simplefilter("ignore")
                p = backbone(model, harmonics=case.harmonics, max_amplitude=max_gaps * model.gap,
                             follow="path", callback=_limited(time_limit), **(options or {}))
            clean = _at_amplitude_bound(Status.parse(p.status)) and not [
                f for f in p.metadata.get("checks", []) if f["kind"] == "left_family"]
        except (Exception, _TimeLimit):  # noqa: BLE001
            clean = False
        out.path_completed = bool(clean)
        if clean:
            out.same_as_path = bool(completed and abs(out.frequency / float(p.frequency[-1]) - 1) < 1e-6)
    return out


def _at_amplitude_bound(status) -> bool:
    """The status (a :class:`~mmshbm.core.status.Status`) says the branch reached its
    bound on the amplitude."""
    from mmshbm.core.status import Status

    return status.kind == Status.BOUND and status.detail == "amplitude"


def _run_one(args):
    case, kw = args
    return run_case(case, **kw)


def run_corpus(cases: list[CorpusCase], *, workers: int = 1, progress=None, **kw) -> list[CaseResult]:
    """:func:`run_case` for every case (in ``workers`` processes when > 1), in order."""
    if workers <= 1:
        out = []
        for case in cases:
            out.append(run_case(case, **kw))
            if progress is not None:
                progress(out[-1])
        return out
    import concurrent.futures as cf

    with cf.ProcessPoolExecutor(workers) as pool:
        out = []
        for r in pool.map(_run_one, [(c, kw) for c in cases], chunksize=4):
            out.append(r)
            if progress is not None:
                progress(r)
        return out


def summary(results: list[CaseResult], slowest: int = 5) -> str:
    """A plain-text report: completion per kind and contact type (and overall for
    one-sided and clearance models), exceptions, time per model, each failure's
    reason, the slowest runs and, when compared, agreement with plain path following."""
    lines = []
    groups = {}
    for r in results:
        groups.setdefault((r.case.kind, r.case.contact), []).append(r)
    lines.append(f"{'kind':<6} {'contact':<10} {'models':>6} {'complete':>9} {'rate':>7} {'median s':>9} "
                 f"{'max s':>7}")
    for (kind, contact), rs in sorted(groups.items()):
        done = sum(r.completed for r in rs)
        t = [r.seconds for r in rs]
        lines.append(f"{kind:<6} {contact:<10} {len(rs):>6} {done:>9} {100 * done / len(rs):>6.1f}% "
                     f"{np.median(t):>9.3f} {max(t):>7.2f}")
    for contact in CONTACTS:
        rs = [r for r in results if r.case.contact == contact]
        if rs:
            done = sum(r.completed for r in rs)
            lines.append(f"all    {contact:<10} {len(rs):>6} {done:>9} {100 * done / len(rs):>6.1f}%")
    n_exc = sum(r.raised for r in results)
    ended = sum(r.family_ended for r in results)
    if ended:
        lines.append(f"family ended (the starting mode's orbit loses the fundamental's majority, no orbit "
                     f"with it found beyond): {ended}")
    over = sum(r.seconds > 30.0 for r in results)
    over_cpu = sum(r.cpu_seconds > 30.0 for r in results)
    total = sum(r.seconds for r in results)
    cpu = [r.cpu_seconds for r in results if math.isfinite(r.cpu_seconds)]
    lines.append(f"exceptions: {n_exc}; runs over 30 s: {over} (processor time over 30 s: {over_cpu}, "
                 f"longest {max(cpu, default=math.nan):.1f} s); total {total:.1f} s, "
                 f"mean {total / max(len(results), 1):.3f} s per model")
    compared = [r for r in results if r.path_completed]
    if compared:
        same = sum(bool(r.same_as_path) for r in compared)
        lines.append(f"plain path following reached the bound without a tongue in {len(compared)}: "
                     f"the default gives the same branch in {same}")
    failures = [r for r in results if not r.completed]
    if failures:
        lines.append("failures:")
        reasons = {}
        for r in failures:
            reasons.setdefault(r.reason, []).append(r)
        for reason, rs in sorted(reasons.items(), key=lambda kv: -len(kv[1])):
            lines.append(f"  {len(rs):>4} x {reason}: " + ", ".join(r.case.label for r in rs[:6])
                         + (" ..." if len(rs) > 6 else ""))
    lines.append("slowest:")
    for r in sorted(results, key=lambda r: -r.seconds)[:slowest]:
        lines.append(f"  {r.seconds:7.2f} s  {r.case.label}  {r.status[:60]}")
    return "\n".join(lines)
