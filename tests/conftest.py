"""Suite-wide: end the process promptly once pytest is done when Blender's bpy module is loaded.

bpy 4.5 can deadlock in a C++ static destructor at process exit (a file-closing thread's condition
variable, seen with gdb), after every test has passed. The suite's result is final by then, so exit
with pytest's status without running the C exit handlers.
"""

import os
import sys

import pytest

_status = {}


def pytest_sessionfinish(session, exitstatus):
    _status["code"] = int(exitstatus)


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    if "bpy" in sys.modules and "code" in _status:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_status["code"])
