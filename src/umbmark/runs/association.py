"""Matching ground truth to wheel samples in time, and saying how well it matched.

Wheel encoders and ground truth (motion capture, localization) are sampled on their own
clocks. Every wheel sample inside the ground truth's time span gets the ground-truth pose
interpolated linearly between the two ground-truth samples around it (headings
unwrapped first), provided those two are at most ``max_gap`` apart; other wheel samples
get no ground truth (NaN). The odometry always integrates every wheel sample.

The association is explicit: :class:`Association` counts the matched samples, gives the
largest gap in the ground truth and the overlap, and :func:`associate` refuses, with a
message, a recording whose two series do not overlap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError, option
from umbmark.model.recording import DEFAULT_MAX_GAP, PoseSeries, WheelSeries

__all__ = ["Association", "associate", "summarize"]


@dataclass(frozen=True)
class Association:
    """How wheel samples and ground truth matched.

    Attributes
    ----------
    matched, total : int
        Wheel samples that got ground truth, and all wheel samples.
    largest_gap : float
        Largest interval between consecutive ground-truth samples inside the overlap [s].
    overlap : tuple of float
        Start and end of the time span both series cover [s].
    max_gap : float
        The gap [s] beyond which no pose was interpolated.
    """

    matched: int
    total: int
    largest_gap: float
    overlap: tuple[float, float]
    max_gap: float

    @property
    def fraction(self) -> float:
        """Share of wheel samples with ground truth."""
        return self.matched / self.total if self.total else 0.0

    def describe(self) -> str:
        """One line for people."""
        return (
            f"{self.matched} of {self.total} wheel samples matched ground truth "
            f"({100 * self.fraction:.1f} %), largest ground-truth gap {self.largest_gap:.3f} s"
        )

    def to_dict(self) -> dict[str, object]:
        """JSON-ready figures."""
        return {
            "matched": self.matched,
            "total": self.total,
            "largest_gap": self.largest_gap,
            "overlap": list(self.overlap),
            "max_gap": self.max_gap,
        }


def associate(
    wheels: WheelSeries,
    truth: PoseSeries,
    *,
    max_gap: float = DEFAULT_MAX_GAP,
    source: str = "",
) -> tuple[FloatArray, Association]:
    """Ground truth at the wheel sample times.

    Returns
    -------
    poses : array, shape (n, 3)
        Interpolated ``x, y, theta`` (theta unwrapped) at each wheel time; NaN rows where
        no ground truth matched.
    association : Association

    Raises
    ------
    InputError
        If the two series do not overlap in time, or no wheel sample matched.
    """
    wt, gt = wheels.time, truth.time
    start, end = max(wt[0], gt[0]), min(wt[-1], gt[-1])
    if start > end or gt.size < 2:
        raise InputError(
            f"wheel data ({wt[0]:.3f} to {wt[-1]:.3f} s) and ground truth "
            f"({gt[0]:.3f} to {gt[-1]:.3f} s) do not overlap in time; are both on the same "
            f"clock (see {option('time_source')})?",
            source=source or None,
        )
    theta = np.unwrap(truth.poses[:, 2])
    j = np.clip(np.searchsorted(gt, wt, side="right") - 1, 0, gt.size - 2)
    t0, t1 = gt[j], gt[j + 1]
    inside = (wt >= gt[0]) & (wt <= gt[-1])
    ok = inside & ((t1 - t0) <= max_gap)
    w = np.where(t1 > t0, (wt - t0) / np.where(t1 > t0, t1 - t0, 1.0), 0.0)[:, None]
    values = np.column_stack([truth.poses[:, :2], theta])
    poses = (1.0 - w) * values[j] + w * values[j + 1]
    poses[~ok] = np.nan
    within = (gt >= start) & (gt <= end)
    gaps = np.diff(gt[within]) if within.sum() > 1 else np.array([end - start])
    association = Association(
        matched=int(ok.sum()),
        total=int(wt.size),
        largest_gap=float(gaps.max()) if gaps.size else 0.0,
        overlap=(float(start), float(end)),
        max_gap=max_gap,
    )
    if association.matched == 0:
        raise InputError(
            f"no wheel sample has ground truth within {max_gap:g} s (largest ground-truth "
            f"gap {association.largest_gap:.3f} s); raise {option('max_gap')} or check the "
            "recording",
            source=source or None,
        )
    return poses, association


def summarize(associations: list[tuple[str, Association]]) -> list[str]:
    """Lines for people: one for all recordings that matched completely, one per other."""
    complete = [(n, a) for n, a in associations if a.matched == a.total]
    lines = []
    if complete:
        total = sum(a.total for _, a in complete)
        gap = max(a.largest_gap for _, a in complete)
        which = complete[0][0] if len(complete) == 1 else f"{len(complete)} recordings"
        lines.append(
            f"{which}: all {total} wheel samples matched ground truth, largest "
            f"ground-truth gap {gap:.3f} s"
        )
    lines += [f"{n}: {a.describe()}" for n, a in associations if a.matched != a.total]
    return lines
