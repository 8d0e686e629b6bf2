"""OpenBLAS's kernels chosen from the CPU's instruction sets (apps/__init__.py): a CPU newer than
Debian 12's OpenBLAS is taken for a Prescott (SSE3 kernels) unless OPENBLAS_CORETYPE says
otherwise; a value the user set wins."""
import os
import subprocess
import sys

import pytest

from helpers import ROOT
from apps import cpu_flags, openblas_core

AVX512 = {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl", "avx2", "fma", "sse3"}


@pytest.mark.parametrize("flags,core", [
    (AVX512, "SKYLAKEX"),
    (AVX512 - {"avx512vl"}, "HASWELL"),          # AVX-512 without VL: the AVX2 kernels
    ({"avx2", "fma", "avx", "sse3"}, "HASWELL"),
    ({"avx2", "sse3"}, None),                    # no FMA: OpenBLAS's own choice
    (set(), None),
])
def test_the_kernel_family_follows_the_instruction_sets(flags, core):
    assert openblas_core(flags) == core


def test_the_flags_are_the_first_processors(tmp_path):
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nflags\t\t: fpu sse3 avx2 fma\n\nprocessor\t: 1\nflags\t\t: fpu\n")
    assert cpu_flags(str(info)) == {"fpu", "sse3", "avx2", "fma"}
    assert cpu_flags(str(tmp_path / "none")) == set()


def _core_of_a_program(**env) -> str:
    """The core OpenBLAS reports (OPENBLAS_VERBOSE=2) in a process that imports apps, then numpy."""
    environ = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    p = subprocess.run([sys.executable, "-c", "import apps, numpy"], capture_output=True, text=True,
                       cwd=ROOT, env=dict(environ, OPENBLAS_VERBOSE="2", **env), timeout=60)
    assert p.returncode == 0, p.stderr
    return p.stdout + p.stderr


def test_a_program_runs_the_chosen_kernels_and_the_users_choice_wins():
    chosen = openblas_core(cpu_flags())
    if chosen is not None:                       # this machine: SkylakeX (Debian's OpenBLAS: Prescott)
        assert f"Core: {chosen}".lower() in _core_of_a_program().lower()
    assert "core: haswell" in _core_of_a_program(OPENBLAS_CORETYPE="Haswell").lower()
