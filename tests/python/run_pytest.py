"""Runs one pytest file of the Python module's tests for ctest: exit 77 (ctest's skip) with a
line saying why where pytest or numpy is missing, or where every test of the file skipped."""

import sys

SKIP = 77

try:
    import numpy  # noqa: F401
    import pytest
except ImportError as missing:
    print(f"skipped: {missing.name} is not installed for {sys.executable} (Debian: python3-{missing.name})")
    sys.exit(SKIP)


class Outcomes:
    """Counts the tests that ran and those that skipped."""

    def __init__(self):
        self.ran = 0
        self.skipped = 0

    def pytest_collectreport(self, report):  # a whole file skipped (pytest.importorskip)
        if report.skipped:
            self.skipped += 1

    def pytest_runtest_logreport(self, report):
        if report.skipped:
            self.skipped += 1
        elif report.when == "call":
            self.ran += 1


outcomes = Outcomes()
status = pytest.main([*sys.argv[1:], "-q", "-rs", "-p", "no:cacheprovider"], plugins=[outcomes])
NO_TESTS_COLLECTED = 5
if status in (0, NO_TESTS_COLLECTED) and outcomes.ran == 0 and outcomes.skipped > 0:
    print("skipped: every test of this file skipped (the reasons are above)")
    sys.exit(SKIP)
sys.exit(status)
