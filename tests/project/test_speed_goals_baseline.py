"""benchmarks/speed_goals.py: the goal-time baseline (issue 13) and the label comparison.

No timing is asserted here (the benchmark prints them); these check the parts that decide
what a verdict means: which labels count as the same answer, and that a missing commit
gives a reason instead of a baseline.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from bench_module import benchmark_module

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "speed_goals.py"


@pytest.fixture(scope="module")
def speed_goals():
    with benchmark_module("speed_goals") as module:
        yield module


def test_equal_labels_pass(speed_goals):
    labels = ["no impact", "1/1", "aperiodic", "1/1"]
    ok, how = speed_goals.compare_labels(labels, labels, labels)
    assert ok and how.startswith("labels 4/4 equal") and how.endswith("0 unexplained")


def test_unsettled_is_explained_only_by_an_old_rule_match(speed_goals):
    today = ["1/1", "unsettled", "1/1"]
    ok, how = speed_goals.compare_labels(today, ["1/1", "2/4", "1/1"], ["1/1", "2/4", "1/1"])
    assert ok and "1 'unsettled'" in how
    # the old rule says aperiodic there: today's "unsettled" is not explained
    ok, _ = speed_goals.compare_labels(today, ["1/1", "aperiodic", "1/1"],
                                       ["1/1", "aperiodic", "1/1"])
    assert not ok


def test_a_different_motion_is_explained_only_after_aperiodic_motion(speed_goals):
    today = ["1/1", "aperiodic", "1/4", "1/4", "no impact"]
    old = ["1/1", "aperiodic", "aperiodic", "1/4", "no impact"]
    ok, how = speed_goals.compare_labels(today, today, old)
    assert ok and "1 after aperiodic motion" in how
    # the difference carries on while the states differ
    old_longer = ["1/1", "aperiodic", "aperiodic", "1/3", "no impact"]
    ok, how = speed_goals.compare_labels(today, today, old_longer)
    assert ok and "2 after aperiodic motion" in how
    # the same difference after periodic motion is not explained
    ok, how = speed_goals.compare_labels(["1/1", "1/4"], ["1/1", "1/4"], ["1/1", "1/3"])
    assert not ok and how.endswith("1 unexplained")


def test_missing_commit_gives_a_reason(speed_goals):
    tree, why = speed_goals.baseline_tree("0" * 40)
    assert tree is None
    assert ("is not in the git repository" in why or "not in a git repository" in why
            or "git is not installed" in why)


def test_goal_commit_is_extracted_with_its_layout(speed_goals):
    root = BENCH.parent.parent
    try:
        found = subprocess.run(["git", "-C", str(root), "rev-parse", "--verify", "--quiet",
                                f"{speed_goals.GOAL_COMMIT}^{{commit}}"], capture_output=True)
    except FileNotFoundError:
        pytest.skip("git is not installed")
    if found.returncode != 0:
        pytest.skip(f"commit {speed_goals.GOAL_COMMIT} is not in this checkout's repository")
    tree, why = speed_goals.baseline_tree(speed_goals.GOAL_COMMIT)
    assert tree is not None, why
    assert why == speed_goals.GOAL_COMMIT
    # the layout of that commit, which the child process uses
    assert (tree / "rattle_lab" / "sdf" / "simulate.py").is_file()
    assert (tree / "rattle_lab" / "thresholds.py").is_file()
    assert (tree / "rattle_lab" / "fit" / "_ramp_model.py").is_file()
    assert speed_goals.baseline_tree(speed_goals.GOAL_COMMIT) == (tree, why)   # reused
