"""Run a tool under Debian's Python when the `python3` first on PATH lacks its packages.

Debian's python3-h5py, python3-numpy and python3-matplotlib belong to /usr/bin/python3, which may not be the
`python3` first on PATH. A tool imports its packages in a try block and, on ImportError, calls
reexec_or_exit: the tool is started again under /usr/bin/python3 (once: an environment variable named after
the tool stops a loop), or, when that is where it already runs, it exits with status 2 and the apt-get line.
Standard library only (it runs before the packages are there)."""
import os
import sys

SYSTEM_PYTHON = "/usr/bin/python3"


def reexec_or_exit(tool_file, missing, packages):
    """`tool_file`: the tool's __file__; `missing`: the ImportError; `packages`: Debian package names."""
    name = os.path.basename(tool_file)
    flag = "CGD_REEXEC_" + os.path.splitext(name)[0].upper()
    if os.path.realpath(sys.executable) != os.path.realpath(SYSTEM_PYTHON) and os.path.exists(SYSTEM_PYTHON) \
            and not os.environ.get(flag):
        os.environ[flag] = "1"
        os.execv(SYSTEM_PYTHON, [SYSTEM_PYTHON, os.path.abspath(tool_file)] + sys.argv[1:])
    modules = ", ".join(p.replace("python3-", "") for p in packages)
    sys.stderr.write(f"{name}: needs {modules} ({missing}); apt-get install {' '.join(packages)}\n")
    sys.exit(2)
