"""`suite_batch.load` without dm_control: a clear error saying what to install."""


def test_without_dm_control_load_says_what_to_install(fresh_python):
    result = fresh_python(
        """
        import sys
        sys.modules["dm_control"] = None  # no dm_control installed
        import suite_batch
        try:
            suite_batch.load("cartpole", "swingup", 2)
        except ImportError as error:
            print(error)
        """
    )
    assert result.returncode == 0, result.stderr
    assert "dm_control's own suite, which is not installed" in result.stdout
    assert "pip install dm-control" in result.stdout
