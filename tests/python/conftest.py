# The ftctune module's tests (tests/CMakeLists.txt runs them with /usr/bin/python3, the build's
# package on PYTHONPATH and --ftctune naming the build's CLI, which the tests compare against).
import copy
import json
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def pytest_configure(config):
    # The runs' own warnings (a parameter on its bound, ...) are the tuning's, not the tests';
    # pytest.warns still sees them where a test asks.
    config.addinivalue_line("filterwarnings", "ignore::ftctune.RunWarning")


def pytest_addoption(parser):
    parser.addoption("--ftctune", default=str(ROOT / "build" / "tools" / "ftctune"),
                     help="the ftctune executable of the same build")


@pytest.fixture(scope="session")
def cli(request):
    return request.config.getoption("--ftctune")


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def table1_path():
    return str(ROOT / "jobs" / "table1.json")


@pytest.fixture(scope="session")
def small_robust():
    """jobs/robust-faults.json made small: 6 members, 4 bats for 2 iterations."""
    job = json.loads((ROOT / "jobs" / "robust-faults.json").read_text())
    job["name"] = "robust-small"
    job["ensemble"]["count"] = 6
    job["tuning"]["algorithm"] = {"type": "bat", "population": 4, "iterations": 2}
    return job


@pytest.fixture
def robust_dict(small_robust):
    return copy.deepcopy(small_robust)
