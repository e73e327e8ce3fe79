"""geotex.malloc: the command line keeps freed memory in the process (glibc)."""

import os
import subprocess
import sys

import pytest

CODE = ("from geotex.malloc import keep_freed_memory; print(keep_freed_memory())")


def _run(env):
    proc = subprocess.run([sys.executable, "-c", CODE], env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_thresholds_set_on_linux_unless_the_user_set_malloc_variables():
    env = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    assert _run(env) == "True"
    assert _run(dict(env, MALLOC_ARENA_MAX="2")) == "False"
