"""A left-associative chain of 16,000 terms, one a line, as MatIEC's parser takes it: the builtin's C used
to nest one parenthesis per operator and crash gcc; it now goes through temporaries (codegen.CHAIN_CHUNK)
with each operator's own C, so the intermediates wrap and fault as before. The program is generated here.
(MatIEC's lexer stops at about 64 KiB of one statement, "flex scanner push-back overflow": the terms are
kept short.)"""

from __future__ import annotations

import pytest

from linmot_st.plc import Plc, PlcFault
from linmot_st.toolchain.builtin import codegen
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text

TERMS = 16_000
HEADER_LINES = 3        # PROGRAM, VAR, `s := x` (the first term)


def _program(terms: list[str], decls: str) -> str:
    body = "\n".join(terms)
    return f"""PROGRAM lc_main
VAR {decls} END_VAR
s := x
{body};
END_PROGRAM
CONFIGURATION lc_cfg
  RESOURCE lc_res ON PLC
    TASK lc_task(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM lc_inst WITH lc_task : lc_main;
  END_RESOURCE
END_CONFIGURATION
"""


def _wrap16(v: int) -> int:
    return (v + 32768) % 65536 - 32768


def test_the_chain_is_longer_than_one_chunk():
    assert TERMS > 10 * codegen.CHAIN_CHUNK


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_a_sum_of_16000_terms_builds_and_wraps_as_int(backend, tmp_path):
    # x = 30: the partial sums leave INT's range many times; + and - wrap modulo 2**16 on both backends
    terms = ["+x" if i % 3 else f"-{i % 7}" for i in range(1, TERMS)]
    plc = Plc(build_text(_program(terms, "s : INT; x : INT := 30;"), tmp_path, backend))
    plc.step(1)
    expected = 30 + sum(30 if i % 3 else -(i % 7) for i in range(1, TERMS))
    assert expected > 32767
    assert plc["LC_INST.S"] == _wrap16(expected)


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_a_division_by_zero_deep_in_a_long_chain_faults_at_its_line(backend, tmp_path):
    at = TERMS - 100      # in the last chunk but one or later
    terms = ["/z" if i == at else "+x" for i in range(1, TERMS)]
    plc = Plc(build_text(_program(terms, "s : DINT; x : DINT := 1; z : DINT;"), tmp_path, backend))
    with pytest.raises(PlcFault) as info:
        plc.step(1)
    assert info.value.kind == 1
    if backend == "builtin":   # the line of the division's left operand, `+x` (MatIEC's is the statement's)
        assert info.value.line == HEADER_LINES + at - 1
