"""Shared fixtures of the Python module's tests: the flashgs binary and the demo scene."""

import os
import subprocess

import pytest

import flashgs
from support import DEMO_CAMERAS, DEMO_SCENE


@pytest.fixture(scope="session")
def cli():
    """Runs the flashgs binary (FLASHGS_CLI, set by ctest); returns the CompletedProcess."""
    path = os.environ.get("FLASHGS_CLI")
    if not path:
        pytest.skip("FLASHGS_CLI is not set (ctest sets it to the flashgs binary)")

    def run(*args, expect_ok=True):
        done = subprocess.run([path, *map(str, args)], capture_output=True, text=True, timeout=300)
        if expect_ok:
            assert done.returncode == 0, f"flashgs {' '.join(map(str, args))} failed:\n{done.stderr}"
        return done

    return run


@pytest.fixture(scope="session")
def demo_scene():
    return flashgs.load_scene(str(DEMO_SCENE))


@pytest.fixture(scope="session")
def demo_cameras():
    return flashgs.load_cameras(str(DEMO_CAMERAS))
