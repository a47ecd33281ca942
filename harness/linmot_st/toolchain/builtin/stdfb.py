"""The standard function blocks (IEC 61131-3 2nd edition), written in ST and compiled with the user's code.

Their behaviour is that of MatIEC's standard library, on purpose, so that both backends agree:
F_TRIG fires on its first call when CLK is FALSE (`Q := NOT CLK AND NOT M`), the timers are state
machines that read the PLC clock `__CURRENT_TIME` once per call, and CTU/CTD/CTUD count on the rising
edge of their inputs through an R_TRIG instance. The variable names (IN, PT, Q, ET, STATE, PREV_IN,
CURRENT_TIME, START_TIME, CU_T, CD_T...) are MatIEC's too, so IEC paths reach the same members on
both backends. Only the blocks a program uses are compiled.
"""

from __future__ import annotations

import functools
import re

_EDGE = """
FUNCTION_BLOCK R_TRIG
  VAR_INPUT CLK : BOOL; END_VAR
  VAR_OUTPUT Q : BOOL; END_VAR
  VAR M : BOOL; END_VAR
  Q := CLK AND NOT M;
  M := CLK;
END_FUNCTION_BLOCK

FUNCTION_BLOCK F_TRIG
  VAR_INPUT CLK : BOOL; END_VAR
  VAR_OUTPUT Q : BOOL; END_VAR
  VAR M : BOOL; END_VAR
  Q := NOT CLK AND NOT M;
  M := NOT CLK;
END_FUNCTION_BLOCK

FUNCTION_BLOCK SR
  VAR_INPUT S1 : BOOL; R : BOOL; END_VAR
  VAR_OUTPUT Q1 : BOOL; END_VAR
  Q1 := S1 OR (NOT R AND Q1);
END_FUNCTION_BLOCK

FUNCTION_BLOCK RS
  VAR_INPUT S : BOOL; R1 : BOOL; END_VAR
  VAR_OUTPUT Q1 : BOOL; END_VAR
  Q1 := NOT R1 AND (S OR Q1);
END_FUNCTION_BLOCK
"""

# the three timers share their variables; STATE: 0 idle, 1 timing, 2 elapsed
_TIMER_VARS = """
  VAR_INPUT IN : BOOL; PT : TIME; END_VAR
  VAR_OUTPUT Q : BOOL; ET : TIME; END_VAR
  VAR STATE : SINT; PREV_IN : BOOL; CURRENT_TIME : TIME; START_TIME : TIME; END_VAR
  CURRENT_TIME := __CURRENT_TIME;
"""

_TIMERS = f"""
FUNCTION_BLOCK TP
{_TIMER_VARS}
  IF STATE = 0 AND NOT PREV_IN AND IN THEN
    STATE := 1;
    Q := TRUE;
    START_TIME := CURRENT_TIME;
  ELSIF STATE = 1 THEN
    IF START_TIME + PT <= CURRENT_TIME THEN
      STATE := 2;
      Q := FALSE;
      ET := PT;
    ELSE
      ET := CURRENT_TIME - START_TIME;
    END_IF;
  END_IF;
  IF STATE = 2 AND NOT IN THEN
    ET := T#0s;
    STATE := 0;
  END_IF;
  PREV_IN := IN;
END_FUNCTION_BLOCK

FUNCTION_BLOCK TON
{_TIMER_VARS}
  IF STATE = 0 AND NOT PREV_IN AND IN THEN
    STATE := 1;
    Q := FALSE;
    START_TIME := CURRENT_TIME;
  ELSIF NOT IN THEN
    ET := T#0s;
    Q := FALSE;
    STATE := 0;
  ELSIF STATE = 1 THEN
    IF START_TIME + PT <= CURRENT_TIME THEN
      STATE := 2;
      Q := TRUE;
      ET := PT;
    ELSE
      ET := CURRENT_TIME - START_TIME;
    END_IF;
  END_IF;
  PREV_IN := IN;
END_FUNCTION_BLOCK

FUNCTION_BLOCK TOF
{_TIMER_VARS}
  IF STATE = 0 AND PREV_IN AND NOT IN THEN
    STATE := 1;
    START_TIME := CURRENT_TIME;
  ELSIF IN THEN
    ET := T#0s;
    STATE := 0;
  ELSIF STATE = 1 THEN
    IF START_TIME + PT <= CURRENT_TIME THEN
      STATE := 2;
      ET := PT;
    ELSE
      ET := CURRENT_TIME - START_TIME;
    END_IF;
  END_IF;
  Q := IN OR STATE = 1;
  PREV_IN := IN;
END_FUNCTION_BLOCK
"""


def _counters(suffix: str, t: str) -> str:
    return f"""
FUNCTION_BLOCK CTU{suffix}
  VAR_INPUT CU : BOOL; R : BOOL; PV : {t}; END_VAR
  VAR_OUTPUT Q : BOOL; CV : {t}; END_VAR
  VAR CU_T : R_TRIG; END_VAR
  CU_T(CLK := CU);
  IF R THEN
    CV := 0;
  ELSIF CU_T.Q AND CV < PV THEN
    CV := CV + 1;
  END_IF;
  Q := CV >= PV;
END_FUNCTION_BLOCK

FUNCTION_BLOCK CTD{suffix}
  VAR_INPUT CD : BOOL; LD : BOOL; PV : {t}; END_VAR
  VAR_OUTPUT Q : BOOL; CV : {t}; END_VAR
  VAR CD_T : R_TRIG; END_VAR
  CD_T(CLK := CD);
  IF LD THEN
    CV := PV;
  ELSIF CD_T.Q AND CV > 0 THEN
    CV := CV - 1;
  END_IF;
  Q := CV <= 0;
END_FUNCTION_BLOCK

FUNCTION_BLOCK CTUD{suffix}
  VAR_INPUT CU : BOOL; CD : BOOL; R : BOOL; LD : BOOL; PV : {t}; END_VAR
  VAR_OUTPUT QU : BOOL; QD : BOOL; CV : {t}; END_VAR
  VAR CD_T : R_TRIG; CU_T : R_TRIG; END_VAR
  CD_T(CLK := CD);
  CU_T(CLK := CU);
  IF R THEN
    CV := 0;
  ELSIF LD THEN
    CV := PV;
  ELSIF NOT (CU_T.Q AND CD_T.Q) THEN
    IF CU_T.Q AND CV < PV THEN
      CV := CV + 1;
    ELSIF CD_T.Q AND CV > 0 THEN
      CV := CV - 1;
    END_IF;
  END_IF;
  QU := CV >= PV;
  QD := CV <= 0;
END_FUNCTION_BLOCK
"""


SOURCE_NAME = "<standard function blocks>"


@functools.lru_cache(maxsize=1)
def source() -> str:
    parts = [_EDGE, _TIMERS]
    for suffix, t in (("", "INT"), ("_DINT", "DINT"), ("_LINT", "LINT"), ("_UDINT", "UDINT"), ("_ULINT", "ULINT")):
        parts.append(_counters(suffix, t))
    return "\n".join(parts)


@functools.lru_cache(maxsize=1)
def names() -> frozenset[str]:
    """The standard FBs' names (the checker asks for each identifier it declares)."""
    return frozenset(re.findall(r"^FUNCTION_BLOCK (\w+)", source(), re.M))


# blocks MatIEC has beyond the standard ones; the builtin compiler does not provide them
NON_STANDARD = {"RTC", "SEMA", "PID", "RAMP", "HYSTERESIS", "INTEGRAL", "DERIVATIVE"}
