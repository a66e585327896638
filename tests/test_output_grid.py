"""The instrument's output step found from the class's own readings, on readings GyroLab
did not make: the tests' noise generator (white and flicker noise, tests/noise_sources.py)
shown on a display of step q (rounded to the nearest multiple, not the simulator's angle
pulses), typed as people round it.  bench/bench_evidence.py --no-grid measures the rates
on whole simulated classes."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from app.core.data_evidence import off_grid
from app.core.output_grid import GridPart, class_step, on_step, part_candidate
from app.review.evidence import SessionEvidence, class_grid_findings, finding_text
from app.web.i18n import translator
from tests.noise_sources import static_record

MEANS = (11.0, 0.3, -11.0, -0.3)


def shown(seed: int, step: float, count: int = 12) -> list[np.ndarray]:
    """One part as a display of ``step`` °/h shows it: four positions of ``count``."""
    record = static_record(4 * count / 0.1 / 3600.0, 0.1, arw=0.05, flicker=0.03, seed=seed)
    return [
        np.round((record[k * count : (k + 1) * count] - 10.0 + m) / step) * step
        for k, m in enumerate(MEANS)
    ]


def typed(positions: list[np.ndarray], decimals: int | None) -> list[np.ndarray]:
    return [v if decimals is None else np.round(v, decimals) for v in positions]


def honest_class(step: float, groups: int = 12, decimals=(None, 3, 2)) -> list[list]:
    return [typed(shown(seed, step), decimals[seed % len(decimals)]) for seed in range(groups)]


def invented(seed: int) -> list[np.ndarray]:
    """Numbers made up around the positions' means, written to 2 decimals."""
    rng = np.random.default_rng(1000 + seed)
    return [np.round(m + rng.uniform(-0.2, 0.2, 12), 2) for m in MEANS]


def together(part: list[np.ndarray]) -> np.ndarray:
    return np.concatenate(part)


def test_the_step_of_a_display_is_found_and_honest_parts_lie_on_it():
    for step in (0.1, 0.025, 0.0036):
        parts = honest_class(step)
        # the characterisation's quantisation term, as an Allan fit estimates it: 20 % off
        found = class_step([together(p) for p in parts], model_step=1.2 * step)
        assert found == pytest.approx(step, rel=1e-6), step
        assert not any(off_grid("heading", p, found) for p in parts)


def test_invented_averaged_and_shifted_readings_fall_between_the_steps():
    parts = honest_class(0.1)
    averaged = [np.round(np.convolve(v, np.ones(3) / 3, "valid"), 2) for v in shown(99, 0.1)]
    shifted = [v + 0.03 for v in shown(98, 0.1)]
    for planted in (invented(0), invented(1), averaged, shifted):
        step = class_step([together(p) for p in [*parts, planted]], model_step=0.1)
        assert step == pytest.approx(0.1)
        assert off_grid("heading", planted, step), planted


def test_no_one_is_flagged_where_the_class_does_not_share_one_step():
    # two instruments, half the class each: whatever step the class shows, every honest
    # part lies on it or is too coarse to test (0.1 °/h steps read as one decimal)
    mixed = honest_class(0.1, groups=6) + honest_class(0.036, groups=6)
    step = class_step([together(p) for p in mixed])
    assert step is None or not any(off_grid("heading", p, step) for p in mixed)
    assert class_step([together(p) for p in honest_class(0.05, 6) + honest_class(0.036, 6)]) is None
    # an unquantised output
    floats = [shown(seed, 1e-12) for seed in range(12)]
    assert class_step([together(p) for p in floats]) is None
    # too few parts to say
    assert class_step([together(p) for p in honest_class(0.1, groups=7)]) is None


def test_a_round_step_is_the_instruments_only_where_its_model_says_so():
    """Most of a class type two decimals of a 0.0036 °/h display and a tenth type three:
    0.01 is the class's rounding, not the gyro's step, and the three-decimal typists are
    honest.  A round step is taken only where the characterisation's quantisation agrees."""
    parts = [typed(shown(seed, 0.0036), 3 if seed % 10 == 0 else 2) for seed in range(30)]
    wholes = [together(p) for p in parts]
    assert class_step(wholes, model_step=0.0036) is None
    assert class_step(wholes) is None
    teaching = [together(p) for p in honest_class(0.1)]
    assert class_step(teaching) is None  # no quantisation term: 0.1 may be rounding
    assert class_step(teaching, model_step=0.3) is None  # a factor 3 off
    assert class_step(teaching, model_step=0.07) == pytest.approx(0.1)


def test_rounding_coarser_than_the_step_hides_it_and_flags_no_one():
    """A class that typed one decimal of a 0.036 °/h display: the step it shows is its
    rounding, which is no test of anyone's readings (q < 2u)."""
    parts = honest_class(0.036, decimals=(1,))
    step = class_step([together(p) for p in parts])
    assert step is None or not any(off_grid("heading", p, step) for p in parts)
    # one decimal of a 0.036 grid lies within 0.05 of one of its multiples: on it
    assert on_step(together(parts[0]), 0.036) == 1.0


def test_a_part_proposes_its_smallest_gap_only_when_its_readings_lie_on_it():
    assert part_candidate(together(shown(1, 0.025))) == pytest.approx(0.025)
    assert part_candidate(np.array([1.0, 1.0, 1.1])) is None  # two values
    # the smallest gap is 0.1, but only 4 of the 7 readings are multiples of it
    assert part_candidate(np.array([0.0, 0.1, 0.35, 0.6, 0.85, 1.1, 1.35])) is None


def rows_of(parts: dict[int, list[np.ndarray]]) -> list:
    rows = []
    for session_id, positions in parts.items():
        evidence = SessionEvidence(
            readings={"heading": GridPart.of(together(positions))}, model_step=0.09
        )
        rows.append(SimpleNamespace(session=SimpleNamespace(id=session_id), data_evidence=evidence))
    return rows


@pytest.mark.parametrize("language", ["en", "zh-CN"])
def test_the_class_tables_finding_names_the_step_in_the_teachers_language(language):
    parts = dict(enumerate(honest_class(0.1), start=1))
    parts[99] = invented(5)
    found = class_grid_findings(rows_of(parts))
    assert list(found) == [99]
    [finding] = found[99]
    assert finding["check"] == "off_class_grid" and finding["step"] == pytest.approx(0.1)
    text = finding_text(finding, translator(language))
    assert "0.1 °/h" in text and "%" in text
    # the simulated gyro's grid is known: no readings kept, nothing found from the class
    assert class_grid_findings(rows_of({})) == {}
