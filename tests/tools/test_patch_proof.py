"""tools.patch_proof proves value-only attributes and refuses those the compiler derives."""

import pytest

from tools import patch_proof


@pytest.mark.patch_table
def test_colour_and_geom_size_are_proven_and_positions_are_refused_with_their_fields():
    proven, refused = patch_proof._verdicts(
        patch_proof.prove({("geom", "rgba"), ("geom", "size"), ("geom", "pos"), ("body", "pos")})
    )
    # A size moves the body's inertia and the model's statistics: mj_setConst must follow.
    assert proven == {("geom", "rgba"): False, ("geom", "size"): True}
    # A geom's position moves its body's inertial frame; a body's, derived constants.
    assert "body_ipos" in refused["geom", "pos"]
    assert "body_invweight0" in refused["body", "pos"]


def test_candidates_are_float_attributes_of_compiled_objects():
    candidates = patch_proof._candidates()
    assert {("geom", "rgba"), ("joint", "damping"), ("motor", "ctrlrange")} <= candidates
    # Names, references and keywords are never candidates.
    assert not {("geom", "name"), ("geom", "material"), ("geom", "type")} & candidates
