"""What the Ray tests share: waiting, with a bound, for Ray to notice that an actor died."""

import time


def wait_until_dead(ray, actor, timeout: float = 30.0) -> None:
    """Returns once calls to `actor` fail with RayActorError; AssertionError after `timeout` s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            ray.get(actor.__ray_ready__.remote(), timeout=10)
        except ray.exceptions.RayActorError:
            return
        time.sleep(0.02)
    raise AssertionError(f"{actor} still alive after {timeout:g} s")
