"""Identifiers: reserved words, standard names, MatIEC's and C's names an identifier cannot take."""

from __future__ import annotations

import functools
import json
from pathlib import Path

from .. import ast as A
from .. import matiec_c_macros, stdfb
from .. import stdfuncs as SF
from .. import types as T

KEYWORDS = {
    "ACTION", "END_ACTION", "ARRAY", "OF", "AT", "CASE", "ELSE", "END_CASE", "CONFIGURATION", "END_CONFIGURATION",
    "CONSTANT", "EN", "ENO", "EXIT", "FALSE", "F_EDGE", "FOR", "TO", "BY", "DO", "END_FOR", "FUNCTION",
    "END_FUNCTION", "FUNCTION_BLOCK", "END_FUNCTION_BLOCK", "IF", "THEN", "ELSIF", "END_IF", "INITIAL_STEP",
    "END_STEP", "NOT", "MOD", "AND", "XOR", "OR", "PROGRAM", "WITH", "END_PROGRAM", "R_EDGE", "READ_ONLY",
    "READ_WRITE", "REPEAT", "UNTIL", "END_REPEAT", "RESOURCE", "ON", "END_RESOURCE", "RETAIN", "NON_RETAIN",
    "RETURN", "STEP", "STRUCT", "END_STRUCT", "TASK", "TRANSITION", "FROM", "END_TRANSITION", "TRUE", "TYPE",
    "END_TYPE", "VAR", "END_VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL",
    "VAR_ACCESS", "VAR_CONFIG", "VAR_GLOBAL", "WHILE", "END_WHILE", "CONTINUE", "REF_TO", "TIME_OF_DAY",
    "DATE_AND_TIME", "EXTENDS", "IMPLEMENTS", "METHOD", "END_METHOD", "INTERFACE", "END_INTERFACE", "THIS",
    "SUPER", "POINTER", "REFERENCE", "NULL",
}


# parameters MatIEC accepts as identifiers although they look reserved
NOT_RESERVED = {"Q", "IN", "PT", "PRIORITY", "INTERVAL", "SINGLE"}


# words the builtin knows only to explain them (types and object-oriented constructs outside the subset)
# that iec2c, with the build's flags (no -r), reads as ordinary identifiers: it builds them as the name of
# a variable, field, POU, type, enumerated value, task, resource or instance (tests/toolchain/builtin/test_builtin_matiec_names.py)
MATIEC_IDENTIFIERS = {
    "CHAR", "WCHAR", "LTIME", "LDATE", "LTOD", "LDT", "LTIME_OF_DAY", "LDATE_AND_TIME",
    "METHOD", "END_METHOD", "INTERFACE", "END_INTERFACE", "EXTENDS", "IMPLEMENTS", "THIS", "SUPER",
    "POINTER", "REFERENCE", "REF_TO",
}


@functools.lru_cache(maxsize=1)
def matiec_library_names() -> frozenset[str]:
    """Identifiers of MatIEC's standard library that cannot name a POU, a type or the configuration
    (matiec_lib_names.json says why)."""
    data = json.loads((Path(__file__).parent.parent / "matiec_lib_names.json").read_text())
    return frozenset(data["names"])


# what iec2c writes into its C under the ST name itself (enumerated values, program instances, resources, the
# configuration and its globals get a prefix there): these cannot take a C macro's name. A global's VAR_EXTERNAL
# is a variable, so only a global that no POU uses can be named so
C_NAMED = {"variable", "field", "type", "function", "function block", "program", "task"}


# MatIEC's library declares these blocks beyond IEC's (stdfb.NON_STANDARD), and iec2c knows their names before
# it reads the user's code: as a user's identifier each is a syntax error (or an internal error of iec2c)
NON_STANDARD_NAME = ("'{name}' cannot name {what}: it is the name of a function block of MatIEC's own library "
                     "(not an IEC standard block, and not provided by the builtin compiler), which iec2c refuses "
                     "as an identifier; choose another name")


def _a(noun: str) -> str:
    return ("an " if noun[0] in "aeiou" else "a ") + noun


class NameRules:
    def check_identifier(self, name: str, pos: A.Pos, what: str) -> str:
        k = name.upper()
        if "__" in name and not self._std_mode:
            self.error(pos, f"identifier '{name}' contains a double underscore, which MatIEC rejects")
        if k in NOT_RESERVED:
            return k
        reserved = k in KEYWORDS or k in T.ELEMENTARY or k in T.ELEMENTARY_ALIASES or k in T.UNSUPPORTED_ELEMENTARY
        if reserved and k not in MATIEC_IDENTIFIERS:
            self.error(pos, f"'{name}' is a reserved word and cannot name a {what}")
        if (SF.is_std_function(k) or k in SF.MISSING_IN_MATIEC_C) and not (what == "function" and k in SF.USER_NAMEABLE):
            self.error(pos, f"'{name}' is the name of a standard function and cannot name a {what}")
        if k in stdfb.NON_STANDARD and what != "field" and not self._std_mode:
            self.error(pos, NON_STANDARD_NAME.format(name=name, what=_a(what)))
        if k in stdfb.names() and what != "field" and not self._std_mode:
            self.error(pos, f"'{name}' is the name of a standard function block and cannot name {_a(what)} (MatIEC "
                            "refuses it: iec2c reads the name as the block's)")
        if k in matiec_c_macros.names() and what in C_NAMED and not self._std_mode:
            self.error(pos, f"'{name}' cannot name {_a(what)}: it is a C macro of the headers MatIEC's generated C "
                            f"includes, and iec2c writes the name into that C as it is ({k}), where the preprocessor "
                            "replaces it and the C does not compile; choose another name")
        if k in self.config_names and what != "configuration" and not self._std_mode:
            self.error(pos, f"'{name}' is the name of the CONFIGURATION and cannot name a {what} (MatIEC rejects "
                            "it: with -p, iec2c knows the configuration's name before it reads the POUs)")
        return k

    def check_global_name(self, name: str, pos: A.Pos, what: str) -> str:
        k = self.check_identifier(name, pos, what)
        if k in matiec_library_names() and not self._std_mode:
            self.error(pos, f"'{name}' cannot name a {what}: it is a variable name in MatIEC's standard library, "
                            "and iec2c -p (which the build uses, as Beremiz does) then fails to parse that library "
                            "('standard_functions.txt: invalid input variable(s) declaration'); choose a longer name")
        if k in self.types:
            self.error(pos, f"'{name}' is already declared as a type")
        if k in self.pous:
            self.error(pos, f"'{name}' is already declared as a {self.pous[k].kind}")
        return k
