"""The external corpus in the test command (../shared/data/truthcases; the
flow and the corpus README's checks are in truthcase_flow.py). Skipped, with
the reason, when ../shared is absent.

Each case runs the rounds a user runs (diagnose, add the best candidate
while it helps, then the final joint re-fit) once per session; the tests
read the outcome: rank, drop and parameters for each case, the true model in
gearsim with its compliant structure within 1.2x of the floor, and the
evidence of every candidate of every round adding up."""

from __future__ import annotations

import pytest
import truthcase_flow as tc
from evidence_checks import assert_evidence_adds_up

from gearsim.analysis import compare

pytestmark = pytest.mark.skipif(
    not tc.corpus_present(),
    reason=f"the external corpus is not at {tc.CORPUS} (../shared is not part of the repository)",
)


@pytest.mark.parametrize("case", tc.CASES)
def test_true_model_in_gearsim_within_1_2x_its_floor(case):
    _, meas, inputs = tc.record(case)
    nrmse = compare(tc.true_model(case), meas, inputs, regimes=False).nrmse
    assert nrmse <= 1.2 * tc.floor(case), f"{nrmse:.4f} = {nrmse / tc.floor(case):.2f}x the floor"


@pytest.mark.parametrize("case", tc.CASES)
def test_case_passes_the_readme_checks(case):
    run = tc.run_case(case)
    print(run.summary())
    assert run.rank_ok, f"rank: {run.rounds}, still missing {run.missing}"
    assert run.drop_ok, run.summary()
    assert run.params_ok, run.params


@pytest.mark.parametrize("case", tc.CASES)
def test_evidence_of_every_candidate_adds_up(case):
    run = tc.run_case(case)
    dt = tc.record(case)[1].dt
    seen = set()
    for d in run.diagnoses:
        for c in d.candidates:
            seen.add(c.effect)
            assert_evidence_adds_up(c.evidence, c.parameters, dt)
    assert seen, "every round lists its candidates"
