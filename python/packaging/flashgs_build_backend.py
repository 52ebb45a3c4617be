"""The PEP 517 build backend of the flashgs Python package: CMake builds the extension, this file
packs it with the package's Python files into a wheel.

It needs nothing beyond the standard library (pyproject.toml asks for no build requirements),
so `pip install .` works offline, with only Debian's packages: scikit-build-core is not packaged
for Debian 12, and setuptools would have to be fetched into pip's isolated build environment.
"""

import base64
import hashlib
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
import zipfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
NAME = "flashgs"
SUMMARY = "FlashGS: a 3D Gaussian Splatting renderer (CPU and CUDA) for Python"


def _version():
    """The project's version, as CMakeLists.txt's project() states it."""
    text = (ROOT / "CMakeLists.txt").read_text()
    match = re.search(r"project\(flashgs\b[^)]*\bVERSION\s+([0-9.]+)", text)
    if not match:
        raise RuntimeError(f"{ROOT / 'CMakeLists.txt'}: project() states no VERSION")
    return match.group(1)


def _tag():
    """This interpreter's wheel tag, e.g. cp311-cp311-linux_x86_64 (the extension is built for it)."""
    python = f"cp{sys.version_info.major}{sys.version_info.minor}"
    platform = sysconfig.get_platform().replace("-", "_").replace(".", "_")
    return f"{python}-{python}-{platform}"


def _dist_info_name():
    return f"{NAME}-{_version()}.dist-info"


def _metadata_files():
    """dist-info file name -> text, RECORD left out."""
    metadata = (f"Metadata-Version: 2.1\nName: {NAME}\nVersion: {_version()}\nSummary: {SUMMARY}\n"
                "Requires-Python: >=3.8\nRequires-Dist: numpy\n")
    wheel = f"Wheel-Version: 1.0\nGenerator: flashgs_build_backend\nRoot-Is-Purelib: false\nTag: {_tag()}\n"
    return {"METADATA": metadata, "WHEEL": wheel}


def _build_extension():
    """Builds flashgs._flashgs with CMake; returns the folder holding the package (build/python/flashgs).

    FLASHGS_PYTHON_BUILD_DIR names an already configured build folder to use as it is;
    otherwise build/pip-<tag> in the repository is configured for this interpreter.
    FLASHGS_CMAKE_ARGS adds CMake arguments (e.g. -DFLASHGS_WITH_CUDA=OFF).
    """
    given = os.environ.get("FLASHGS_PYTHON_BUILD_DIR")
    build = pathlib.Path(given) if given else ROOT / "build" / f"pip-{_tag()}"
    if not given:
        generator = ["-G", "Ninja"] if shutil.which("ninja") else []
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), *generator, "-DCMAKE_BUILD_TYPE=Release",
                        "-DFLASHGS_PYTHON=ON", "-DFLASHGS_BUILD_TESTS=OFF", "-DFLASHGS_BUILD_APP=OFF",
                        f"-DPython_EXECUTABLE={sys.executable}",
                        *shlex.split(os.environ.get("FLASHGS_CMAKE_ARGS", ""))], check=True)
    subprocess.run(["cmake", "--build", str(build), "--target", "_flashgs"], check=True)
    package = build / "python" / NAME
    if not list(package.glob("_flashgs*.so")):
        raise RuntimeError(f"{package}: no _flashgs extension was built; CMake's output says why "
                           "(Python's headers or pybind11 missing? Debian: python3-dev python3-pybind11)")
    return package


def _record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def get_requires_for_build_wheel(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    folder = pathlib.Path(metadata_directory) / _dist_info_name()
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in _metadata_files().items():
        (folder / name).write_text(text)
    return folder.name


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    package = _build_extension()
    wheel_name = f"{NAME}-{_version()}-{_tag()}.whl"
    files = {f"{NAME}/{path.name}": path.read_bytes() for path in sorted(package.iterdir()) if path.is_file()}
    dist_info = _dist_info_name()
    for name, text in _metadata_files().items():
        files[f"{dist_info}/{name}"] = text.encode()
    record = [_record_line(name, data) for name, data in files.items()] + [f"{dist_info}/RECORD,,"]
    files[f"{dist_info}/RECORD"] = ("\n".join(record) + "\n").encode()
    target = pathlib.Path(wheel_directory) / wheel_name
    partial = target.with_name(target.name + ".part")  # written whole, then renamed
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as wheel:
        for name, data in files.items():
            wheel.writestr(name, data)
    partial.replace(target)
    return wheel_name
