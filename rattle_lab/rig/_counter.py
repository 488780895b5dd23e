"""Counting the rig's stage evaluations (tests prove that skipped stages never run)."""

from __future__ import annotations

from collections import Counter


class StageCounter:
    """Counts how often each synthesis stage ran.

    Stages: ``simulate`` (simulator calls), ``motion_dense`` (dense motion sampled),
    ``base``, ``plate``, ``velocity``, ``mic``, ``drive`` (channels synthesised),
    ``acoustic`` (the acoustic model evaluated for one run).

    Examples
    --------
    >>> c = StageCounter()
    >>> c.add("mic"); c["mic"], c["plate"]
    (1, 0)
    """

    def __init__(self) -> None:
        self.counts: Counter[str] = Counter()

    def add(self, stage: str, n: int = 1) -> None:
        """Count ``n`` evaluations of ``stage``."""
        self.counts[stage] += n

    def __getitem__(self, stage: str) -> int:
        return self.counts[stage]

    def __repr__(self) -> str:
        return f"StageCounter({dict(self.counts)})"
