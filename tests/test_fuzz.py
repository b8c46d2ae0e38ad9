"""A short fuzz run over every public function (about a minute in all); scripts/fuzz.py is the
long one. The cases (tests/fuzz_cases.py) mutate saved decompositions (dropped, trimmed,
extended or retyped arrays, NaN and inf, indices out of range, truncated or flipped bytes,
garbage JSON) and draw extreme point sets (tiny, huge, 1e-300 and 1e300 scales, duplicates,
collinear, planar, a few points) and parameters. Each must end in a finite result, a
ValueError or pointscale.Cancelled. A crash ends the test run, which is a failure too.

The runs are random (derandomize=False); on a failure hypothesis prints the falsifying case,
whose repr reproduces it (`from fuzz_cases import *; run(<case>)`), and a @reproduce_failure blob.
"""
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

import fuzz_cases

STRATEGIES = fuzz_cases.case_strategies(scale=0.5)

# Examples per function, sized so that the whole file takes about a minute on the 2-core
# reference machine: the functions that decompose get fewer.
EXAMPLES = {"decompose": 300, "decompose_rayshoot": 200, "encode": 300, "morph": 300, "coarse_base_warning": 300}
DEFAULT_EXAMPLES = 550


@pytest.mark.parametrize("function", sorted(STRATEGIES))
def test_every_case_ends_in_a_finite_result_a_value_error_or_cancelled(function):
    @settings(max_examples=EXAMPLES.get(function, DEFAULT_EXAMPLES), deadline=None, database=None,
              derandomize=False, print_blob=True, suppress_health_check=list(HealthCheck))
    @given(data=st.data())
    def run(data):
        case = data.draw(STRATEGIES[function], label="case")
        note(f"reproduce: from fuzz_cases import *; run({case!r})")
        fuzz_cases.run(case)  # raises fuzz_cases.Failure on anything else

    run()


def test_the_cases_reach_valid_calls_too():
    """The harness must not only feed the functions garbage: a good share of drawn decompose and
    reconstruct cases run through to a finite result."""
    outcomes = []

    @settings(max_examples=40, deadline=None, database=None, derandomize=False,
              suppress_health_check=list(HealthCheck))
    @given(case=st.one_of(STRATEGIES["decompose"], STRATEGIES["reconstruct"]))
    def run(case):
        outcomes.append(fuzz_cases.run(case))

    run()
    assert outcomes.count("ok") >= 5, outcomes
