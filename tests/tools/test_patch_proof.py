"""tools.patch_proof proves value-only attributes and refuses those the compiler derives."""

import pytest

from tools import patch_proof


@pytest.mark.patch_table
def test_colour_is_proven_and_geom_size_and_body_pos_are_refused_with_their_fields():
    proven, refused = patch_proof._verdicts(
        patch_proof.prove({("geom", "rgba"), ("geom", "size"), ("body", "pos")})
    )
    assert proven == {("geom", "rgba"): False}
    # A sphere's size also sets the scene's extent; a body's position changes derived constants.
    assert "stat.extent" in refused["geom", "size"]
    assert "body_invweight0" in refused["body", "pos"]


def test_candidates_are_float_attributes_of_compiled_objects():
    candidates = patch_proof._candidates()
    assert {("geom", "rgba"), ("joint", "damping"), ("motor", "ctrlrange")} <= candidates
    # Names, references and keywords are never candidates.
    assert not {("geom", "name"), ("geom", "material"), ("geom", "type")} & candidates
