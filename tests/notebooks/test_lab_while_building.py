"""``make lab`` opens before the students' wheel is built, on an environment without ``course_lib``.

On a fresh clone the students' wheel takes minutes to compile. ``autograder lab --student-env``
then starts JupyterLab at once in the students' environment holding the wheel's requirements
only (:func:`student_bundle.ensure_student_requirements`, which also removes a wheel of other
sources: it may hold a function graded since), and builds and installs the wheel behind it
(:class:`autograder.lab.WheelInstall`), saying what it waits for and when it is ready. With the
wheel already built, nothing changes: it is installed before the server starts.

The build, the installs and the server are replaced by recorders: what is checked is which
environment the server is started in, and in what order things happen.
"""

from __future__ import annotations

import types
from pathlib import Path

import pytest

from autograder import lab, student_bundle


@pytest.fixture
def recorded(monkeypatch, tmp_path):
    """Every build, install and server start of a launch, in order."""
    events = []
    wheel = tmp_path / "build" / "4f9_course_student-0.1.0+gabc-cp311-cp311-linux_x86_64.whl"
    state = {"cached": None}
    monkeypatch.setattr(lab, "cached_wheel", lambda cache: state["cached"])
    monkeypatch.setattr(lab, "build_wheel", lambda cache: events.append(("build", cache)) or wheel)
    monkeypatch.setattr(lab, "ensure_student_env",
                        lambda env, w: events.append(("install wheel", w)) or env / "bin/python")
    monkeypatch.setattr(lab, "ensure_student_requirements",
                        lambda env: events.append(("install requirements",)) or env / "bin/python")
    course = types.SimpleNamespace(root=tmp_path / "course",
                                   release_dir=tmp_path / "course" / "release" / "tripos2006")
    monkeypatch.setattr(lab, "prepare_course", lambda root: course)

    class Server:
        def __init__(self, cmd, **kwargs):
            events.append(("server", cmd[0], kwargs["env"].get("PYTHONPATH")))

    monkeypatch.setattr(lab.subprocess, "Popen", Server)
    monkeypatch.setattr(lab.WheelInstall, "start", lambda self: events.append(("start", self)))
    return events, state, wheel


def _launch(tmp_path):
    return lab.launch("student", tmp_path / "course", config_dir=tmp_path / "config",
                      student_env=tmp_path / "env", build_cache=tmp_path / "build")


def test_a_wheel_to_build_is_built_after_the_server_starts_without_course_lib(
        recorded, tmp_path, capsys):
    events, _, wheel = recorded
    _launch(tmp_path)
    assert [e[0] for e in events] == ["install requirements", "server", "start"]
    assert events[1][1:] == (str(tmp_path / "env" / "bin/python"), None)   # no PYTHONPATH
    pending = events[2][1]
    pending.run()                    # what the thread does once started
    assert [e[0] for e in events[3:]] == ["build", "install wheel"]
    assert events[3][1] == tmp_path / "build" and events[4][1] == wheel
    said = capsys.readouterr().err
    assert said.index(lab.WAITING) < said.index(lab.READY)
    assert pending.error is None


def test_a_built_wheel_is_installed_before_the_server_starts(recorded, tmp_path):
    events, state, wheel = recorded
    state["cached"] = wheel
    _launch(tmp_path)
    assert events == [("install wheel", wheel), ("server", str(tmp_path / "env" / "bin/python"),
                                                 None)]


def test_a_failed_build_is_said_and_kept(recorded, tmp_path, monkeypatch, capsys):
    events, _, _ = recorded

    def broken(cache):
        raise student_bundle.WheelLeak("course_lib/x.py: source of a compiled module")

    monkeypatch.setattr(lab, "build_wheel", broken)
    _launch(tmp_path)
    pending = events[-1][1]
    pending.run()
    assert isinstance(pending.error, student_bundle.WheelLeak)
    said = capsys.readouterr().err
    assert "could not be built" in said and lab.READY not in said
    assert not [e for e in events if e[0] == "install wheel"]


def test_the_requirements_environment_drops_a_wheel_of_other_sources(monkeypatch, tmp_path):
    calls = []
    monkeypatch.setattr(student_bundle, "_make_env", lambda env, base: env / "bin/python")
    monkeypatch.setattr(student_bundle, "_pip", lambda env, *args: calls.append(args))
    env = tmp_path / "env"
    env.mkdir()
    (env / student_bundle.WHEEL_STAMP).write_text("4f9_course_student-0.1.0+gold.whl")
    python = student_bundle.ensure_student_requirements(env)
    assert python == env.resolve() / "bin/python"
    assert calls[0] == ("uninstall", "--yes", student_bundle.DIST_NAME)
    assert calls[1] == ("install", "--no-compile", *student_bundle.student_requirements())
    assert not (env / student_bundle.WHEEL_STAMP).exists()
    student_bundle.ensure_student_requirements(env)      # nothing left to do
    assert len(calls) == 2
    assert not any(Path(a).suffix == ".whl" for call in calls for a in call)
