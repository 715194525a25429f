"""Contract of an integrator plugin: advance y' = f(t, y) and sample it at output times."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np

from gyrolab.contracts.integrator_rules import checked
from gyrolab.kernels.model import CompiledModel

RightHandSide = Callable[[float, np.ndarray], np.ndarray]
ProgressCallback = Callable[[float], None]


@dataclass
class IntegratorStats:
    """Work done by one integration; ``n_rejected`` is None where the method does not report it."""

    nfev: int
    n_steps: int
    n_rejected: int | None
    wall_time: float
    njev: int = 0
    nlu: int = 0

    def attributes(self) -> dict[str, Any]:
        """netCDF-safe attributes (unknown counts are left out, not stored as a fake number)."""
        # getattr over the fields: dataclasses.asdict deep-copies every value
        values = ((f.name, getattr(self, f.name)) for f in fields(self))
        return {f"integrator_{k}": v for k, v in values if v is not None}


@dataclass
class Choice:
    """C7: what an integrator that chooses its method ran in one ``integrate`` call, returned with the ``Solution``
    (nothing of a call is kept on the integrator). ``gyrolab.accuracy`` measures ``method``'s run and rechecks
    ``promised`` against the measurement; the dataset stores ``attributes``."""

    #: the method that ran (None: no integration, an analytic series, measured against ``check``)
    method: Integrator | None
    #: dataset attributes saying what was chosen and why (``auto_method``, ``auto_precision``, ...)
    attributes: dict[str, Any]
    #: the target asked for (``accuracy``) and the max-norm error promised at every output time (None: no promise)
    target: float | None = None
    promised: float | None = None
    #: whether the run may climb the precision ladder (``Integrator.climbed``) when it must be made more accurate
    may_climb: bool = False
    #: with ``method`` None: the more accurate run that measures it, and the run to take instead when it breaks
    check: Integrator | None = None
    instead: Callable[[], Solution] | None = None
    #: the run is kept only where its measured error meets ``promised``, else ``instead`` runs (``auto``'s double run
    #: on a chaotic scene whose predicted round-off asked for double-double, or whose own growth raised its prediction
    #: above the target: ``integrate(..., estimated=True)``)
    measure_first: bool = False


@dataclass(frozen=True)
class OwnEstimate:
    """C8: the run's global error, estimated by the integrator in the same pass (``integrate(..., estimate=True)``)."""

    #: the estimated error of every state component at every output time (exact − computed); None: the growth
    #: alone was measured
    error: np.ndarray | None
    #: ln of how much the motion amplified perturbations by each output time (the running maximum)
    log_growth: np.ndarray
    #: the same by the first tenth of the span (an ``auto`` pilot's end: growth after it beyond a power law is chaos), or
    #: for a resumed run where it resumed (``auto`` resumes at its pilot's end)
    log_growth_tenth: float
    #: accepted steps (the round-off of the run grows with them)
    steps: int
    #: how it was estimated, for the dataset
    how: str
    #: the pass's state at the run's end (the error or an empty array, the unit tangent vector, (ln|δ|, its running
    #: maximum, the round-off's walk so far), the state and its compensation): a run resumed from this one's end
    #: carries it on (``Taylor.integrate(..., resume=...)``)
    end: tuple | None = None
    #: a run whose round-off it measured (the Taylor method with a double-double head): Σ |terms computed in double|
    #: over its steps, a round-off of that many units u of double precision added up coherently (the model's numbers
    #: derived in double err the same way at every step), unamplified; None: not measured
    roundoff: float | None = None


@dataclass
class Solution:
    """Samples of the state at the requested output times."""

    t: np.ndarray  # (n,)
    y: np.ndarray  # (n, state size)
    stats: IntegratorStats
    #: C7: what was chosen and ran (None for an integrator that does not choose)
    choice: Choice | None = None
    #: C8: the run's error estimated in the same pass, when asked (``integrate(..., estimate=True)``)
    estimate: OwnEstimate | None = None


# Capabilities (rule 8 of ``Integrator``): declared by the integrator, asked for by the engine, never its name;
# docs/plugins.md, "Integrator capabilities", says what the engine does with each and which built-ins have it.

#: C1: integrates the system's compiled model (``compiled``) instead of calling ``fun``
COMPILED_MODEL = "compiled_model"
#: C2: integrates the compiled model when the system has one, ``fun`` otherwise
PREFERS_COMPILED_MODEL = "prefers_compiled_model"
#: C3: passes the true time to the right-hand side, so it integrates time-dependent forces
TIME_DEPENDENT = "time_dependent"
#: C4: has a compiled batch kernel, ``integrate_batch``: many trajectories of one compiled model in one call
BATCH_KERNEL = "batch_kernel"
#: C5: its batch kernel advances several trajectories at once in SIMD lanes (vectorised across trajectories)
VECTOR_LANES = "vector_lanes"
#: C6: the chaos indicators' variational equations can run with its method (``variational_settings``)
VARIATIONAL = "variational"
#: C7: picks a method and tolerance itself, per scene (``integrate``) and per batch (``choose_batch_method``)
CHOOSES_METHOD = "chooses_method"
#: C8: ``integrate(..., estimate=True)`` also estimates the run's global error in the same pass (``Solution.estimate``)
ESTIMATES_ERROR = "estimates_error"
#: every capability, in the order the documentation lists them
CAPABILITIES = (COMPILED_MODEL, PREFERS_COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, VARIATIONAL,
                CHOOSES_METHOD, ESTIMATES_ERROR)
#: the precision ladder, lowest rung first: an integrator's ``precision`` names its rung, ``climbed`` goes up one
PRECISIONS = ("double", "double-double")
#: the run dataset's attribute holding the integrator's ``evaluation_label`` (what ``integrator_nfev`` counts)
NFEV_COUNTS_ATTRIBUTE = "integrator_nfev_counts"


@dataclass
class BatchSolution:
    """Many trajectories of one compiled model, from one call of a batch kernel (``Integrator.integrate_batch``)."""

    t: np.ndarray  # (n_out,)
    y: np.ndarray  # (trajectories, n_out, state size)
    n_steps: int  # per trajectory (adaptive kernels: the largest number of any trajectory)
    wall_time: float
    #: (trajectories,) True where the trajectory failed (non-finite, or an adaptive step below the
    #: spacing of floating-point numbers; its rows from then on are NaN); only with ``failures="mark"``,
    #: else all False (a failure raised instead)
    failed: np.ndarray | None = None
    #: (trajectories,) accepted steps of each trajectory (adaptive kernels; None for fixed steps)
    steps: np.ndarray | None = None
    #: the integrator settings the kernel ran with (``auto``: its choice, e.g. ``auto_method``, ``auto_tolerance``)
    settings: dict | None = None

    @property
    def trajectory_steps_per_second(self) -> float:
        total = self.y.shape[0] * self.n_steps if self.steps is None else int(self.steps.sum())
        return total / self.wall_time


@dataclass(frozen=True)
class VariationalSettings:
    """How the chaos indicators' compiled variational kernels run for a VARIATIONAL integrator: fixed-step RK4 with
    ``step`` (the fewest equal steps no longer than it in each output interval), or, with ``step`` None, adaptive
    DOP853 with ``rtol``, ``atol`` and ``max_step``."""

    step: float | None = None
    rtol: float = 1e-10
    atol: float = 1e-10
    max_step: float = np.inf

    @property
    def fixed_step(self) -> bool:
        return self.step is not None


class Integrator(ABC):
    """A method that integrates an initial-value problem.

    Rules for implementers:

    1. ``__init__(self, *, rtol=1e-10, ...)`` takes the plugin's config
       parameters, each a keyword argument with a default (``rtol``/``atol``
       for adaptive methods, ``step`` for fixed-step ones; ``**params`` is
       refused, its keys being unknown), validates them and raises
       ``gyrolab.errors.ConfigError`` on bad values; any other exception is
       reported as one sentence naming the plugin.
    2. ``integrate(fun, t_out, y0)`` returns the state at every time in
       ``t_out`` (increasing, ``t_out[0]`` is the initial time), computed by
       dense output or by landing on those times, never by storing every
       internal step.
    3. It counts its work (``IntegratorStats``: right-hand-side evaluations,
       accepted and rejected steps where known, wall time).
    4. It never returns non-finite values: a failure (step size underflow,
       NaN or inf in the state) raises ``gyrolab.errors.IntegrationError``
       with one sentence saying when and why.
    5. It calls ``progress(t)``, when given, every few steps (cheap; the
       callback decides whether to report).
    6. A compiled integrator (``COMPILED_MODEL``, rule 8) integrates the ``compiled`` model it is given (the
       system's ``compiled_model()``) instead of calling ``fun``.
    7. ``attributes()`` gives its settings for the dataset.
    8. It declares what it can do in ``capabilities`` (a frozenset of this module's capability constants,
       C1–C8, each with its hook; docs/plugins.md, "Integrator capabilities", says what the engine does with
       each) and the engine asks ``supports(capability)``, never for an integrator's name.
       ``evaluation_label``, when set, says what ``nfev`` counts where that is not right-hand-side calls.
    9. ``more_accurate(factor)``, optional: a more accurate run of the same method, which
       ``output.error_estimate`` compares with this one to measure the stored trajectory's error.
    10. ``prepare(system)`` is called once by the scene before integrating
        (default: nothing); ``auto`` uses it to consult the system's regimes.
    11. ``precision`` names its rung on the precision ladder (``PRECISIONS``); ``climbed(factor)``, optional:
        the same method one rung up, which ``gyrolab.accuracy`` runs where ``more_accurate`` has reached its floor.
        A CHOOSES_METHOD integrator returns what it chose with its solution (``Solution.choice``, a ``Choice``);
        ``gyrolab.accuracy`` calls ``integrate(..., estimated=True)`` when it will measure the run, and the
        integrator may then try a cheaper choice first (``Choice.measure_first``).
    12. An ESTIMATES_ERROR integrator's ``integrate(..., estimate=True)`` returns, with the solution, the run's
        global error estimated in the same pass (``Solution.estimate``, an ``OwnEstimate``), which
        ``gyrolab.accuracy`` stores instead of running a companion where the run's round-off is small beside it.

    Every subclass's own ``integrate`` is wrapped when the class is defined (``gyrolab.contracts.integrator_rules``),
    so that each call is checked against rules 2–4; a violation is one ``IntegrationError`` sentence naming the
    integrator (docs/plugins.md, "What the engine checks").
    """

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "integrate" in cls.__dict__:  # the class's own integrate, not an inherited (already wrapped) one
            cls.integrate = checked(cls.__dict__["integrate"])

    name: ClassVar[str]
    adaptive: ClassVar[bool]

    @abstractmethod
    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        """Integrate from t_out[0] and sample the state at t_out."""

    def prepare(self, system: Any) -> None:
        """Called once by the scene with its system, for integrators that need more than the right-hand
        side (``auto`` consults the system's analytic regimes). The default needs nothing."""

    def attributes(self) -> dict[str, Any]:
        return {}

    # Capabilities (rule 8): the declaration and the hooks that go with them.

    #: what this integrator can do: capability constants of this module (rule 8)
    capabilities: ClassVar[frozenset[str]] = frozenset()
    #: what ``nfev`` counts where it is not right-hand-side calls (e.g. "Taylor series evaluations"); None: calls
    evaluation_label: ClassVar[str | None] = None

    @classmethod
    def supports(cls, capability: str) -> bool:
        """Whether the integrator declares ``capability`` in ``capabilities``."""
        if capability not in CAPABILITIES:
            raise ValueError(f"capability {capability!r} is not one of gyrolab's; valid: {', '.join(CAPABILITIES)}")
        return capability in cls.capabilities

    @classmethod
    def refusal(cls, compiled: CompiledModel, system: Any = None) -> str | None:
        """Why this integrator cannot run the compiled model ``compiled`` (of ``system``, for naming its forces), as a
        clause that follows the integrator's name ("evaluates the built-in torque forms only, and ..."); None: it can.
        The scene calls it once, before integrating; an integrator may prepare the model here (compile a kernel)."""
        return None

    def integrate_batch(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray, params: np.ndarray,
                        failures: str) -> BatchSolution:
        """BATCH_KERNEL: the trajectories from the rows of ``y0s`` (trajectories × state size) of ``compiled`` with the
        parameters ``params`` (trajectories × ``compiled.params.size``, one row each), sampled at ``times``.
        The caller has validated the arrays. ``failures="raise"``: a failed trajectory raises IntegrationError;
        ``"mark"``: it is marked in ``BatchSolution.failed`` (NaN rows from its failure on), the others kept."""
        raise NotImplementedError(f"integrator {self.name!r} declares no batch kernel")

    def variational_settings(self) -> VariationalSettings:
        """VARIATIONAL: how the chaos indicators' variational kernels run with this integrator's method and settings."""
        raise NotImplementedError(f"integrator {self.name!r} declares no variational equations")

    def more_accurate(self, factor: float) -> tuple[Integrator, float, str] | None:
        """Rule 9 (``output.error_estimate``): (the same method about ``factor`` times more accurate, the number that
        turns the two runs' difference into this run's error estimate, a few words saying how), or None when it
        cannot be made so (a tolerance already at its floor, or nothing to tighten). A method with tolerances
        divides them by ``factor`` (the number is 1); a fixed-step method of order p halves its step (the number is
        Richardson's 2^p / (2^p − 1)); a method that chooses (CHOOSES_METHOD) returns the method it ran instead."""
        return None

    #: rule 11: its rung on the precision ladder (``PRECISIONS``)
    precision: str = PRECISIONS[0]

    def climbed(self, factor: float) -> tuple[Integrator, float, str] | None:
        """Rule 11: (the same method one rung up the precision ladder, ``factor`` times more accurate, the number
        and words of ``more_accurate``), or None: no higher rung."""
        return None

    def choose_batch_method(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray,
                            params: np.ndarray) -> tuple[Integrator, dict[str, Any]]:
        """CHOOSES_METHOD: (the integrator every trajectory of this batch runs, best one with a batch kernel; the
        choice as dataset attributes), chosen once for the batch of initial states ``y0s`` with parameters
        ``params`` (one row each)."""
        raise NotImplementedError(f"integrator {self.name!r} does not choose a method")
