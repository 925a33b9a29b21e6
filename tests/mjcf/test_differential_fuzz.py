"""Differential fuzzing: our MJCF pipeline decides and compiles every document as MuJoCo does.

Mutated seed models and generated documents (`tools/mjcf_differential.py`) are compiled
by MuJoCo's own parser and by `mjcf.from_path` + `mjcf.Physics.from_mjcf_model`; both must
accept or both reject, and accepted documents must compile to the same sizes and arrays.
The examples are derandomised, so every run checks the same documents; `python -m tools.fuzz N`
runs as many as asked.
"""

import random

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from tools.mjcf_differential import MUTATION_KINDS, SEEDS, Verdict, Workspace, document_for, mutate

EXAMPLES = 1500
_ACCEPTED = (Verdict.AGREE, Verdict.DOCUMENTED)


@pytest.fixture(scope="module")
def workspace():
    space = Workspace()
    yield space
    space.close()


@pytest.mark.parametrize("seed", sorted(SEEDS))
def test_each_seed_model_compiles_to_the_same_model_as_mujoco(workspace, seed):
    result = workspace.run(mutate(seed, "seed", random.Random(0)))
    assert (result.verdict, result.detail) == (Verdict.AGREE, "both accept, same model")


@settings(
    max_examples=EXAMPLES,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(kind=st.sampled_from(MUTATION_KINDS), rng=st.randoms(use_true_random=False))
def test_mutated_documents_get_the_same_decision_and_model_as_mujoco(workspace, kind, rng):
    document = document_for(kind, rng)
    result = workspace.run(document)
    # A document that crashes MuJoCo's own parser (mujoco 3.3.0 raises FatalError on some
    # <layer> mutations) has no MuJoCo decision to agree with; `tools.fuzz` counts them.
    assume(result.verdict != Verdict.MUJOCO_CRASH)
    assert result.verdict in _ACCEPTED, (
        f"{result.verdict.value} [{document.note}]: {result.detail}\n{document.text}"
    )
