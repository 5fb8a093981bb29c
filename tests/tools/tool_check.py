"""What every tool test (tests/tools/*.py) starts from: the source directory (the first argument, as CTest gives it,
else this checkout), tools/ on the import path so that the test can import the tool it tests, and the ok/FAIL line
of each check with the count of failures the test exits on (`sys.exit(1 if failures() else 0)`)."""
import os
import sys

source = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, os.path.join(source, "tools"))
_failures = 0


def check(ok, what):
    """Prints `ok   WHAT` or `FAIL WHAT` and counts a failure."""
    global _failures
    print(("ok   " if ok else "FAIL ") + what)
    _failures += not ok


def failures():
    """The number of failed checks so far."""
    return _failures
