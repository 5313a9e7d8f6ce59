import subprocess
from pathlib import Path

import pytest

from mdle.cli import main
from tests.ros2.conftest import mdle_argv

PLAN = "atom a = (go(0.2 m/s), never, 2 s)\nplan main = (a, stalled, 5 s)\n"


@pytest.fixture
def plan(tmp_path: Path) -> Path:
    p = tmp_path / "p.mdle"
    p.write_text(PLAN)
    return p


def test_a_ros2_option_without_the_ros2_backend_is_refused(
        plan: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(plan), "--ns", "robot1", "--quiet"]) == 1
    assert "--ns is for a ROS 2 robot: it needs --backend ros2" in capsys.readouterr().err
    assert main(["repl", "--use-sim-time", "--plain"]) == 1
    assert "--use-sim-time is for a ROS 2 robot" in capsys.readouterr().err


@pytest.mark.parametrize(("args", "message"), [
    (["--ns", "9lives"], "--ns `9lives`: `9lives` is not a ROS name part"),
    (["--domain-id", "300"], "--domain-id 300 is outside 0..232"),
])
def test_bad_ros2_options_name_the_option(plan: Path, capsys: pytest.CaptureFixture[str],
                                          args: list[str], message: str) -> None:
    assert main(["run", str(plan), "--backend", "ros2", "--quiet", *args]) == 1
    assert message in capsys.readouterr().err


def test_a_robot_that_sends_nothing_is_named_with_its_topics_and_domain(
        plan: Path, dds_env: dict[str, str]) -> None:
    run = subprocess.run(mdle_argv("run", str(plan), "--backend", "ros2", "--ns", "nobody",
                                   "--quiet"), env=dds_env, capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 1, run.stderr
    domain = dds_env["ROS_DOMAIN_ID"]
    assert "nothing arrived on /nobody/odom (nav_msgs/msg/Odometry, DDS topic " \
           "rt/nobody/odom), /nobody/scan" in run.stderr
    assert f"DDS domain {domain}" in run.stderr and "Traceback" not in run.stderr


def test_sim_serve_says_what_it_speaks(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sim", "serve"]) == 2
    assert "--ros2" in capsys.readouterr().err
    assert main(["sim"]) == 2
    assert "mdle sim serve --ros2" in capsys.readouterr().err


@pytest.mark.parametrize(("args", "message"), [
    (["--speed", "0"], "the speed must be in (0, 100], got 0"),
    (["--step", "nan"], "the simulation step must be in (0, 1] s, got nan"),
    (["--cmd-timeout", "-1"], "the command timeout must be 0 (never) or more seconds, got -1"),
    (["--ns", "a b"], "--ns `a b`: `a b` is not a ROS name part"),
])
def test_sim_serve_refuses_bad_numbers_and_names(capsys: pytest.CaptureFixture[str],
                                                 args: list[str], message: str) -> None:
    assert main(["sim", "serve", "--ros2", "--world", "empty", *args]) == 1
    assert message in capsys.readouterr().err
