"""Fuzz: seeded hostile files in every format through ``geotex check``.

Each case must end as exit 0/1 with a report, or exit 2 with exactly one
stderr line ``geotex: error: ...``, within 10 s and 1 GiB, with no traceback
(see :mod:`geotex.fuzzing`; ``benchmarks/fuzz.py`` runs 10,000 cases).
"""

import collections

import pytest

from geotex.fuzzing import FORMATS, FuzzCase, Outcome, make_cases, run_cases, verdict

N_CASES = 300


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    cases = make_cases(tmp_path_factory.mktemp("fuzz"), N_CASES, seed=15)
    # hostile cases in batches of 8 (each with its own seconds and peak): a process per
    # case spent most of this test starting Python, and under load could pass the limit
    return run_cases(cases, hostile_batch=8, workers=2)


def test_every_fuzz_case_ends_cleanly(outcomes):
    bad = [f"{o.case.path.name} ({o.case.mutation}): {verdict(o)}"
           for o in outcomes if verdict(o)]
    assert not bad, f"{len(bad)} of {len(outcomes)} cases misbehaved:\n" + "\n".join(bad)


def test_fuzz_covers_every_format_and_hostile_kind(outcomes):
    seeds = collections.Counter(o.case.seed for o in outcomes)
    assert set(seeds) == set(FORMATS)
    mutations = {o.case.mutation.split("+")[0] for o in outcomes}
    for kind in ("flip", "truncate", "numbers", "indices", "binary-numbers", "header-count",
                 "3mf-bomb", "3mf-declared-size", "3mf-entities", "glb-deep", "glb-uri",
                 "glb-json-values", "glb-counts", "obj-polygon"):
        assert kind in mutations
    assert any("+ext:" in o.case.mutation for o in outcomes)       # wrong extensions
    codes = collections.Counter(o.code for o in outcomes)
    assert codes[2] and codes[1] + codes[0]                       # both kinds happen


def test_cases_are_deterministic(tmp_path):
    a = make_cases(tmp_path / "a", 40, seed=3)
    b = make_cases(tmp_path / "b", 40, seed=3)
    assert [c.path.read_bytes() for c in a] == [c.path.read_bytes() for c in b]


def test_verdict_rejects_bad_outcomes(tmp_path):
    case = FuzzCase(tmp_path / "x.stl", "stl", "flip")

    def outcome(code, out="", err="", seconds=0.1, rss=1 << 20):
        return Outcome(case, code, out, err, seconds, rss)

    assert verdict(outcome(0, "printable: yes\n")) is None
    assert verdict(outcome(2, err="geotex: error: x.stl: bad\n")) is None
    assert verdict(outcome(3, err="geotex: error: internal error: ...\n"))
    assert verdict(outcome(2, err="Traceback (most recent call last):\n  ...\n"))
    assert verdict(outcome(2, err="warning\ngeotex: error: x\n"))
    assert verdict(outcome(1, "no report\n"))
    assert verdict(outcome(None, seconds=10.0))
    assert verdict(outcome(0, "printable: yes\n", seconds=11.0))
    assert verdict(outcome(0, "printable: yes\n", rss=2 << 30))


def test_a_small_child_of_a_large_process_reports_its_own_peak():
    # Linux starts a forked child's ru_maxrss at the parent's size: a test
    # process grown by earlier tests made every fuzz case look like 1 GiB
    import sys

    import numpy as np

    from geotex.fuzzing import limited_env, run_limited

    ballast = np.ones(40_000_000)            # 320 MB in this process
    code, _, _, _, peak = run_limited([sys.executable, "-c", "print(1)"], 60, limited_env())
    assert code == 0 and ballast[0] == 1.0
    assert peak < 150 * 2 ** 20


_PEAK_SCRIPT = """
import numpy as np
from geotex.fuzzing import peak_rss, reset_peak_rss
ballast = np.ones(40_000_000)            # 320 MB, then freed
before = peak_rss()
del ballast
print(reset_peak_rss(), before, peak_rss())
"""


def test_a_batch_reports_each_case_its_own_peak():
    # the high-water mark is reset before each case of a batch, so a large case
    # does not make the small cases after it look large. In a fresh process: a test
    # worker's own peak and allocator settings (geotex.malloc.keep_freed_memory, which
    # in-process CLI tests switch on, keeps freed memory resident) depend on the tests
    # it ran before.
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-c", _PEAK_SCRIPT], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    ok, before, after = proc.stdout.split()
    if ok != "True":
        pytest.skip("this kernel cannot reset the peak (/proc/self/clear_refs)")
    assert int(before) - int(after) > 250 * 2 ** 20
