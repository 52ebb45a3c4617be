"""`pip install .` from the repository into a fresh virtual environment, offline, then a render
through the installed package (the build backend packs the extension the test build made)."""

import os
import pathlib
import subprocess
import sys
import venv

import pytest

from support import DEMO_SCENE, REPOSITORY


def test_pip_install_builds_an_importable_package(tmp_path):
    build_dir = os.environ.get("FLASHGS_PYTHON_BUILD_DIR")
    if not build_dir:
        pytest.skip("FLASHGS_PYTHON_BUILD_DIR is not set (ctest sets it to the test build)")
    environment = tmp_path / "venv"
    try:
        venv.create(environment, system_site_packages=True, with_pip=True)
    except Exception as error:  # Debian splits ensurepip into python3-venv
        pytest.skip(f"cannot make a virtual environment with pip here ({error}; Debian: python3-venv)")
    python = environment / "bin" / "python"
    install = subprocess.run([str(python), "-m", "pip", "install", "--no-index", "--no-cache-dir", str(REPOSITORY)],
                             capture_output=True, text=True, timeout=600,
                             env={**os.environ, "PIP_FIND_LINKS": "", "FLASHGS_PYTHON_BUILD_DIR": build_dir})
    assert install.returncode == 0, install.stdout + install.stderr
    script = ("import flashgs, sys; s = flashgs.load_scene(sys.argv[1]); "
              "c = flashgs.Camera.look_at([0, -1, -3], [0, 0, 0], width=64, height=36); "
              "image, stats = flashgs.render(s, c, backend='cpu'); "
              "print(flashgs.__file__, image.shape, stats.kv_pairs > 0)")
    done = subprocess.run([str(python), "-c", script, str(DEMO_SCENE)], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path, env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    assert done.returncode == 0, done.stderr
    location, rest = done.stdout.split(" ", 1)
    assert pathlib.Path(location).is_relative_to(environment) and rest.strip() == "(36, 64, 3) True"
