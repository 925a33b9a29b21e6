"""The dm_control import redirect serves dm_control.composer/mjcf/mujoco from this project.

Each test runs in a fresh interpreter: the redirect changes the process's import system.
"""

import subprocess
import sys
import textwrap

import pytest


def _run_python(code: str, *args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, *args] if not code else [sys.executable, "-c", code, *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=cwd,
    )


def _dm_control_installed() -> bool:
    probe = "import importlib.util as u; print(u.find_spec('dm_control') is not None)"
    return _run_python(probe).stdout.strip() == "True"


def test_dm_control_names_are_this_projects_modules_after_install():
    result = _run_python(
        textwrap.dedent(
            """
            from composer import dm_control_compat
            dm_control_compat.install()
            from dm_control import composer as dc, mjcf as dm
            from dm_control.composer.observation import observable as dobs
            from dm_control.mjcf import traversal_utils as dtu
            import composer, mjcf
            from composer.observation import observable
            from mjcf import traversal_utils
            print(dc is composer, dm is mjcf, dobs is observable, dtu is traversal_utils)
            print(composer.__spec__.name, observable.__spec__.name)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:2] == [
        "True True True True",
        "composer composer.observation.observable",
    ]


def test_dm_control_mujoco_is_the_engine_package_after_install():
    result = _run_python(
        textwrap.dedent(
            """
            from composer import dm_control_compat
            dm_control_compat.install()
            from dm_control import mujoco
            from dm_control.mujoco.wrapper.mjbindings import enums, mjlib
            import mujoco_physics
            physics = mujoco.Physics.from_xml_string("<mujoco><worldbody><body>"
                "<joint name='j'/><geom size='.1'/></body></worldbody></mujoco>")
            print(mujoco is mujoco_physics, type(physics).__module__)
            print(enums.mjtJoint.mjJNT_HINGE, mjlib.mj_step is mujoco.mj_step)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:2] == ["True mujoco_physics.engine", "3 True"]


def test_rl_control_physics_error_of_an_installed_dm_control_is_ours(tmp_path):
    # A stand-in for an installed dm_control whose rl.control defines its own error and
    # catches it in reset_context, as dm_control's does.
    package = tmp_path / "dm_control"
    (package / "rl").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "rl" / "__init__.py").write_text("")
    (package / "rl" / "control.py").write_text(
        textwrap.dedent(
            """
            class PhysicsError(RuntimeError):
                pass

            def run_catching(function):
                try:
                    function()
                except PhysicsError as error:
                    return f"caught {type(error).__module__}"
            """
        )
    )
    result = _run_python(
        textwrap.dedent(
            f"""
            import sys
            sys.path.insert(0, {str(tmp_path)!r})
            from composer import dm_control_compat
            dm_control_compat.install()
            from dm_control.rl import control
            import mujoco_physics
            physics = mujoco_physics.Physics.from_xml_string("<mujoco><worldbody><body>"
                "<freejoint/><geom size='.1'/></body></worldbody></mujoco>")
            physics.data.qvel[:] = float("inf")
            print(control.PhysicsError is mujoco_physics.PhysicsError)
            print(control.run_catching(physics.step))
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:2] == ["True", "caught mujoco_physics.engine"]


def test_dm_control_inverse_kinematics_is_ours_and_other_utils_stay_dm_controls(tmp_path):
    # A stand-in for an installed dm_control whose utils package has its own modules.
    utils = tmp_path / "dm_control" / "utils"
    utils.mkdir(parents=True)
    (tmp_path / "dm_control" / "__init__.py").write_text("")
    (utils / "__init__.py").write_text("")
    (utils / "rewards.py").write_text("ORIGIN = 'stand-in'\n")
    (utils / "inverse_kinematics.py").write_text("raise ImportError('the stand-in ran')\n")
    result = _run_python(
        textwrap.dedent(
            f"""
            import sys
            sys.path.insert(0, {str(tmp_path)!r})
            from composer import dm_control_compat
            dm_control_compat.install()
            from dm_control.utils import inverse_kinematics as ik, rewards
            import composer.utils.inverse_kinematics
            print(ik is composer.utils.inverse_kinematics, rewards.ORIGIN)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[0] == "True stand-in"


def test_model_built_through_dm_control_names_compiles_and_binds():
    result = _run_python(
        textwrap.dedent(
            """
            from composer import dm_control_compat
            dm_control_compat.install()
            from dm_control import mjcf
            model = mjcf.RootElement()
            body = model.worldbody.add("body", name="ball", pos=[0, 0, 1])
            body.add("freejoint")
            body.add("geom", type="sphere", size=[0.1])
            physics = mjcf.Physics.from_mjcf_model(model)
            physics.step(10)
            print(round(float(physics.bind(body).xpos[2]), 3) < 1.0)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "True"


def test_module_missing_from_this_project_is_a_module_not_found_error():
    result = _run_python(
        textwrap.dedent(
            """
            from composer import dm_control_compat
            dm_control_compat.install()
            try:
                import dm_control.composer.no_such_module
            except ModuleNotFoundError as e:
                print("ModuleNotFoundError", e.name)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ModuleNotFoundError dm_control.composer.no_such_module"


def test_dm_control_viewer_is_this_projects_viewer_and_serves_only_momas_submodules():
    result = _run_python(
        textwrap.dedent(
            """
            from composer import dm_control_compat
            dm_control_compat.install()
            from dm_control import viewer
            from dm_control.viewer import gui, renderer
            from dm_control.viewer import viewer as viewer_module
            import composer.viewer
            print(viewer is composer.viewer, viewer.launch.__module__)
            print(gui.__name__, renderer.__name__, viewer_module.__name__)
            try:
                import dm_control.viewer.application
            except ModuleNotFoundError as e:
                print(e)
            dm_control_compat.uninstall()
            import sys
            print("dm_control.viewer" in sys.modules)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:4] == [
        "True composer.viewer",
        "composer.viewer.gui composer.viewer.renderer composer.viewer.viewer",
        "No module named 'dm_control.viewer.application'",
        "False",
    ]


def test_private_names_that_moma_imports_are_served():
    # MoMa reads dm_control's private class names to annotate and check its arguments.
    result = _run_python(
        textwrap.dedent(
            """
            from composer import dm_control_compat
            dm_control_compat.install()
            from dm_control import mjcf
            from dm_control.composer.initializers import utils
            model = mjcf.RootElement()
            body = model.worldbody.add("body")
            joint = body.add("joint", name="hinge")
            body.add("geom", size=[0.1])
            physics = mjcf.Physics.from_mjcf_model(model)
            print(isinstance(joint, mjcf.element._ElementImpl))
            print(isinstance(physics.bind([]), mjcf.physics._EmptyBinding))
            print(isinstance(physics.bind(joint), mjcf.physics._EmptyBinding))
            print(utils.JointStaticIsolator.__module__)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:4] == [
        "True",
        "True",
        "False",
        "composer.initializers.utils",
    ]


def test_composer_variation_is_an_attribute_after_importing_composer_alone():
    result = _run_python(
        textwrap.dedent(
            """
            from composer import dm_control_compat
            dm_control_compat.install()
            from dm_control import composer
            print(composer.variation.distributions.Uniform(0, 1)(random_state=None) < 1)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "True"


def test_without_install_dm_control_names_are_not_served():
    if _dm_control_installed():
        pytest.skip("dm_control is installed here, so `import dm_control` succeeds on its own")
    result = _run_python(
        "import composer\ntry:\n import dm_control.composer\nexcept ImportError:\n print('no')"
    )
    assert result.stdout.strip() == "no"


def test_bare_dm_control_package_when_dm_control_is_not_installed():
    if _dm_control_installed():
        pytest.skip("dm_control is installed here; the bare stand-in package is not used")
    result = _run_python(
        textwrap.dedent(
            """
            from composer import dm_control_compat
            dm_control_compat.install()
            import dm_control
            from dm_control import composer
            print(composer.Environment.__module__, hasattr(dm_control, "__path__"))
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "composer.environment True"


def test_install_after_real_dm_control_modules_were_imported_is_refused():
    result = _run_python(
        textwrap.dedent(
            """
            import sys, types
            sys.modules["dm_control.mjcf"] = types.ModuleType("dm_control.mjcf")
            from composer import dm_control_compat
            try:
                dm_control_compat.install()
            except RuntimeError as e:
                print("RuntimeError", "dm_control.mjcf" in str(e))
            print(dm_control_compat.installed())
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["RuntimeError", "True", "False"]


def test_uninstall_stops_serving_and_forgets_aliases():
    result = _run_python(
        textwrap.dedent(
            """
            import sys
            from composer import dm_control_compat
            dm_control_compat.install()
            dm_control_compat.install()
            import dm_control.mjcf
            dm_control_compat.uninstall()
            print(dm_control_compat.installed(), "dm_control.mjcf" in sys.modules)
            """
        )
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False False"


def test_python_dash_m_runs_an_unmodified_dm_control_script_with_its_arguments(tmp_path):
    script = tmp_path / "dm_script.py"
    script.write_text(
        textwrap.dedent(
            """
            import sys
            from dm_control import composer, mjcf
            from dm_control.composer.variation import distributions
            import helper_next_to_script
            model = mjcf.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
            print(sys.argv[1:], __name__, helper_next_to_script.VALUE,
                  type(model).__module__, distributions.Uniform.__module__)
            """
        )
    )
    (tmp_path / "helper_next_to_script.py").write_text("VALUE = 7\n")
    result = _run_python("", "-m", "composer.dm_control_compat", str(script), "a", "--b")
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == (
        "['a', '--b'] __main__ 7 mjcf.element composer.variation.distributions"
    )


def test_python_dash_m_without_a_script_prints_usage_and_fails():
    result = _run_python("", "-m", "composer.dm_control_compat")
    assert result.returncode == 2
    assert "usage" in result.stderr
