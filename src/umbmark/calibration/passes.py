"""UMBmark passes on one robot (:class:`Passes`): each pass's calibration in the order
driven, and with a single pass of recorded runs the *predicted* after
(:func:`predict_after`): the same runs' wheel data integrated again with the new
parameters, a prediction, not a measured pass.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from umbmark.calibration.result import CalibrationResult
from umbmark.core.errors import InputError, option
from umbmark.core.jsontext import JsonText
from umbmark.core.messages import info
from umbmark.core.version import __version__
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run
from umbmark.returns.clusters import Benchmark, umbmark_benchmark
from umbmark.runs.read import RunSource, source_name
from umbmark.runs.read_options import ReadOptions, SourceOptions

if TYPE_CHECKING:
    from umbmark.calibration.validation import ValidationReport

__all__ = [
    "Holds",
    "Passes",
    "PredictedPass",
    "calibrate_passes",
    "e_b_words",
    "predict_after",
]


@dataclass(frozen=True)
class PredictedPass:
    """A pass's recorded runs integrated again with its new parameters.

    What the runs' return errors would have been had the odometry used the corrected
    parameters: a prediction from the recorded wheel data, not a measured pass (the
    robot steered by its old odometry, so the paths driven were those of the pass).

    Attributes
    ----------
    runs : tuple of Run
        The pass's square runs, their odometry end poses integrated anew.
    benchmark : Benchmark
        Their UMBmark figures (Eqs. 3.1-3.4).
    params : WheelParams
        The parameters integrated with (:meth:`CalibrationResult.new_params` applied to
        the pass's own, as :func:`umbmark.replay` does).
    """

    runs: tuple[Run, ...]
    benchmark: Benchmark
    params: WheelParams

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres)."""
        bench = self.benchmark
        return {
            "kind": "prediction: the recorded wheel data replayed with the new parameters",
            "e_max_syst": bench.e_max_syst,
            "worst_direction": bench.worst.direction.value,
            "sem": bench.sem,
            "second_pass_threshold": bench.second_pass_threshold,
            **{f"cg_{c.direction.value}": [float(v) for v in c.cg] for c in bench.clusters},
            "runs": [
                {
                    "label": run.label,
                    "direction": run.direction.value,
                    "eps_x": run.return_error[0],
                    "eps_y": run.return_error[1],
                }
                for run in self.runs
            ],
            "parameters": {
                "wheelbase": self.params.wheelbase,
                "wheel_diameter_left": self.params.diameter_left,
                "wheel_diameter_right": self.params.diameter_right,
            },
        }


def predict_after(calibration: CalibrationResult) -> PredictedPass | None:
    """The pass after ``calibration`` as its recorded wheel data predicts it.

    Returns None unless the pass has UMBmark figures and every square run carries its
    recorded wheel data (run logs, OptiOdom sessions, bags; not runs tables).
    """
    if calibration.benchmark is None or calibration.params is None:
        return None
    squares = [run for run in calibration.runs if run.kind == "square"]
    if not squares or any(run.log is None for run in squares):
        return None
    params = calibration.new_params().applied_to(calibration.params)
    runs = tuple(run.reintegrated(params) for run in squares)
    try:
        bench = umbmark_benchmark(runs)
    except ValueError:  # pragma: no cover - the pass had both directions
        return None
    return PredictedPass(runs=runs, benchmark=bench, params=params)


@dataclass(frozen=True)
class Holds:
    """What the robot's controller holds after a self-calibration: the one statement the
    terminal, the JSON, ``overlay.yaml`` and the HTML page all render.

    Attributes
    ----------
    labels : tuple of str
        Every pass's name in the order driven (``pass 1``, ..., ``verification``).
    held : int or None
        The pass (1-based) whose correction the controller holds: the last one applied
        (None: no pass's correction was applied).
    separation_multiplier, c_left, c_right : float
        The multipliers the controller holds (``wheel_separation_multiplier``,
        ``left_wheel_radius_multiplier``, ``right_wheel_radius_multiplier``), as it
        reports them.
    methods : tuple of (str or None)
        How each pass's correction reached the controller (``reconfigure``, ``yaml``,
        ...; None: not applied), as the pass recorded it; empty: not recorded.
    coarse : float or None
        The factor a coarse turning correction multiplied ``wheel_separation_multiplier``
        by before the first pass (None: none applied): the first pass's ``E_b`` is the
        residual on that corrected wheelbase (:func:`e_b_words`).
    """

    labels: tuple[str, ...]
    held: int | None
    separation_multiplier: float
    c_left: float
    c_right: float
    methods: tuple[str | None, ...] = ()
    coarse: float | None = None

    def __post_init__(self) -> None:
        if self.held is not None and not 1 <= self.held <= len(self.labels):
            raise ValueError(f"held pass {self.held} of {len(self.labels)}")

    @property
    def label(self) -> str | None:
        """The name of the pass whose correction the controller holds."""
        return None if self.held is None else self.labels[self.held - 1]

    def applied(self, k: int) -> bool:
        """Whether pass ``k`` (1-based) was applied: passes are applied in order until one
        is not, so every pass up to the held one."""
        return self.held is not None and k <= self.held

    def method(self, k: int) -> str | None:
        """How pass ``k`` (1-based) was applied (None: not applied, or not recorded)."""
        if not self.applied(k):
            return None
        return self.methods[k - 1] if k <= len(self.methods) else None

    def applied_words(self, k: int) -> str:
        """``applied by reconfigure``, ``applied``, or ``not applied``: pass ``k``."""
        if not self.applied(k):
            return "not applied"
        method = self.method(k)
        return "applied" if method is None else f"applied by {method}"

    def multipliers(self) -> dict[str, float]:
        """The multipliers under the controller's parameter names."""
        return {
            "wheel_separation_multiplier": self.separation_multiplier,
            "left_wheel_radius_multiplier": self.c_left,
            "right_wheel_radius_multiplier": self.c_right,
        }

    def words(self) -> str:
        """One sentence for people: which pass's correction, and the multipliers."""
        values = ", ".join(f"{name} {value:.6f}" for name, value in self.multipliers().items())
        if self.label is None:
            return f"The controller holds no correction of these passes: {values}."
        later = [f"{label} (not applied)" for label in self.labels[self.held or 0 :]]
        after = f"; measured after it: {', '.join(later)}" if later else ""
        return f"The controller holds the correction of {self.label}: {values}{after}."

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the pass's name (or None) and the multipliers."""
        return {"pass": self.label, **self.multipliers()}


def e_b_words(e_b: float, coarse: float | None) -> str:
    """``E_b`` as every output shows it: ``0.999890``; measured after a coarse turning
    correction by ``coarse`` (the factor on ``wheel_separation_multiplier``), the residual
    on the corrected wheelbase with the value composed with it beside:
    ``0.999890 residual, 1.099879 composed``."""
    if coarse is None:
        return f"{e_b:.6f}"
    return f"{e_b:.6f} residual, {e_b * coarse:.6f} composed"


@dataclass(frozen=True, repr=False)
class Passes(JsonText):
    """UMBmark passes on one robot, and what the page about them shows (the job's
    :class:`umbmark.jobs.report.PassesReport` adds the page's file).

    Attributes
    ----------
    passes : tuple of CalibrationResult
        Each pass's calibration, in the order driven (pass 1 first).
    predicted : PredictedPass or None
        With a single pass of recorded runs: its runs replayed with the new parameters.
    validation : ValidationReport or None
        Held-out validation of the estimators on the last pass (``validate=True``).
    command : str or None
        The command line (or call) that made the report, for its provenance.
    holds : Holds or None
        After a self-calibration, what the controller holds (the page then shows that
        pass's verdict and overlay); None: the last pass's correction is the one to apply.
    created : datetime
        When the report was made (UTC).
    """

    passes: tuple[CalibrationResult, ...]
    predicted: PredictedPass | None = None
    validation: ValidationReport | None = None
    command: str | None = None
    holds: Holds | None = None
    created: dt.datetime = field(default_factory=lambda: dt.datetime.now(dt.timezone.utc))

    def __repr__(self) -> str:
        figures = ", ".join("None" if e is None else f"{e * 1000:.1f} mm" for e in self.e_max_syst)
        return f"{type(self).__name__}(passes={len(self.passes)}, e_max_syst=[{figures}])"

    @property
    def e_max_syst(self) -> tuple[float | None, ...]:
        """``E_max,syst`` [m] of each pass (Eq. 3.4)."""
        return tuple(p.e_max_syst for p in self.passes)

    @property
    def last(self) -> CalibrationResult:
        """The last pass: its correction is the one to apply now."""
        return self.passes[-1]

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres, radians): what ``report --json`` prints."""
        return {
            "umbmark_version": __version__,
            "units": {"length": "m", "angle": "rad"},
            "command": self.command,
            "e_max_syst": list(self.e_max_syst),
            "passes": [p.to_dict() for p in self.passes],
            "predicted_after": None if self.predicted is None else self.predicted.to_dict(),
            "validation": None if self.validation is None else self.validation.to_dict(),
            "holds": None if self.holds is None else self.holds.to_dict(),
        }


def calibrate_passes(
    sources: Sequence[RunSource],
    options: SourceOptions,
    *,
    side_length: float | None = None,
    wheelbase: float | None = None,
    method: str | None = None,
    fit_truth_offset: bool = False,
    override_verdict: bool = False,
) -> tuple[list[CalibrationResult], SourceOptions]:
    """Each pass calibrated (:func:`umbmark.calibration.sources.calibrate_sources`), in the
    order driven: pass 1 with the parameters ``options`` say were active, pass 2 on with
    the previous pass's new ``c_L``, ``c_R`` and ``wheel_separation_multiplier`` (a note
    says so). Returns the passes and the options the last one was read with.

    Raises
    ------
    InputError
        As the calibration does; and for a pass without square runs in both directions.
    """
    from umbmark.calibration.sources import calibrate_sources

    names = [source_name(s) for s in sources]
    passes: list[CalibrationResult] = []
    pass_options: SourceOptions = options
    for k, (one, name) in enumerate(zip(sources, names, strict=True), 1):
        note = None
        if passes:
            before = passes[-1].calibration
            pass_options = options.copy()
            pass_options["current_c_l"] = before.new_c_left
            pass_options["current_c_r"] = before.new_c_right
            pass_options["current_separation_multiplier"] = before.new_separation_multiplier
            note = info(
                f"taken as active during the runs, pass {k - 1}'s new parameters "
                f"(c_L {before.new_c_left:.6f}, c_R {before.new_c_right:.6f}, "
                f"wheel_separation_multiplier {before.new_separation_multiplier:.6f})"
            )
        result = calibrate_sources(
            [one],
            ReadOptions.of(pass_options),
            side_length=side_length,
            wheelbase=wheelbase,
            method=method,
            fit_truth_offset=fit_truth_offset,
            override_verdict=override_verdict,
        )
        if result.benchmark is None and result.gyro is not None:
            result = _with_square_runs(result, one, pass_options, side_length, wheelbase)
        if result.benchmark is None:
            raise InputError(
                f"pass {k}: UMBmark needs square runs in both directions (cw and ccw), at "
                f"least two each{_ONE_PAGE if result.gyro is not None else ''}",
                source=name,
            )
        if note is not None:
            result = replace(result, notes=(*result.notes, note))
        passes.append(result)
    return passes, pass_options


#: What a recording calibrated by its gyro without square runs does instead of a report.
_ONE_PAGE = (
    f" (a recording calibrated by its gyro: its square runs are read with "
    f"{option('truth_topic')} and {option('side_length')}; without them, umbmark calibrate "
    f"{option('imu_topic')} TOPIC --report PAGE writes its page)"
)


def _with_square_runs(
    result: CalibrationResult,
    source: RunSource,
    options: SourceOptions,
    side_length: float | None,
    wheelbase: float | None,
) -> CalibrationResult:
    """A pass calibrated by its gyro, with the UMBmark figures of the square runs its
    recording holds against its ground truth (read as without the IMU): its runs, their
    ``E_max,syst`` and the parameters they were integrated with, the correction the
    gyro's. Unchanged where the recording holds no square runs in both directions."""
    from umbmark.calibration.sources import calibrate_sources

    plain = {**options, "imu_topic": None, "scan_topic": None}
    try:
        squares = calibrate_sources(
            [source], ReadOptions.of(plain), side_length=side_length, wheelbase=wheelbase
        )
    except InputError:
        return result
    if squares.benchmark is None:
        return result
    said = info(
        f"E_max,syst and the runs: the recording's {len(squares.runs)} runs against its "
        "ground truth; the correction: the gyro's calibration (predicted after: these runs "
        "integrated with it)"
    )
    return replace(
        result,
        runs=squares.runs,
        benchmark=squares.benchmark,
        params=squares.params,
        associations=squares.associations,
        notes=(*result.notes, said),
    )
