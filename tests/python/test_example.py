"""The examples in bindings/python/examples run."""

import os
import subprocess
import sys

import pytest

import aqs

EXAMPLES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(aqs.__file__))),
                        "examples")
SCRIPTS = sorted(f for f in os.listdir(EXAMPLES) if f.endswith(".py"))


@pytest.mark.parametrize("script", SCRIPTS)
def test_example_runs(script):
    bindings = os.path.dirname(EXAMPLES)
    env = dict(os.environ, AQS_LIBRARY=aqs.library_path,
               PYTHONPATH=os.pathsep.join(filter(None, [bindings, os.environ.get("PYTHONPATH")])))
    result = subprocess.run([sys.executable, os.path.join(EXAMPLES, script)], env=env,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.strip()
