"""The bricks of the multi-brick tasks, named as the suite's observation keys expect."""

from manipulation.props import Duplo2x4
from manipulation.tasks import task_constants as tc


def brick_name(index: int) -> str:
    """'duplo2x4', 'duplo2x4_2', 'duplo2x4_4', ...: the scopes of the bricks' observables."""
    return "duplo2x4" if index == 0 else f"duplo2x4_{2 * index}"


def make_bricks(count: int) -> list[Duplo2x4]:
    """`count` differently coloured bricks with guiding studs, so they stack easily."""
    return [
        Duplo2x4(
            name=brick_name(i), rgba=tc.BRICK_COLOURS[i % len(tc.BRICK_COLOURS)], easy_align=True
        )
        for i in range(count)
    ]
