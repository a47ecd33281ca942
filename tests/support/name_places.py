"""The places an identifier can take, as ST sources with {n} for the name, shared by the name tests
(test_builtin_names.py, test_builtin_matiec_refusals.py): each tries names in the places it is about."""

from __future__ import annotations


def name_places(p: str) -> tuple[dict[str, str], str, str, dict[str, str]]:
    """(places, MAIN, CONFIG, NAMES) for the prefix p of the helper names (tn_main, rf_cfg, ...); CONFIG is a
    format string over NAMES."""
    main = f"PROGRAM {p}_main\n  VAR i : INT; END_VAR\n  i := i + 1;\nEND_PROGRAM\n"
    config = ("CONFIGURATION {cfg}\n  {glob}RESOURCE {res} ON PLC\n    TASK {task}(INTERVAL := T#10ms, PRIORITY := 0);\n"
              f"    PROGRAM {{inst}} WITH {{task}} : {p}_main;\n  END_RESOURCE\nEND_CONFIGURATION\n")
    names = {"cfg": f"{p}_cfg", "glob": "", "res": f"{p}_res", "task": f"{p}_task", "inst": f"{p}_inst"}
    places = {
        "function block": "FUNCTION_BLOCK {n}\n  VAR_INPUT a : INT; END_VAR\n  a := a;\nEND_FUNCTION_BLOCK\n" + main,
        "function": "FUNCTION {n} : INT\n  VAR_INPUT a : INT; END_VAR\n  {n} := a;\nEND_FUNCTION\n" + main,
        "program": "PROGRAM {n}\n  VAR i : INT; END_VAR\n  i := 1;\nEND_PROGRAM\n" + main,
        "type": "TYPE {n} : STRUCT a : INT; END_STRUCT; END_TYPE\n" + main,
        "variable": f"PROGRAM {p}_main\n  VAR {{n}} : INT; END_VAR\n  {{n}} := {{n}} + 1;\nEND_PROGRAM\n",
        "output": f"FUNCTION_BLOCK {p}_fb\n  VAR_OUTPUT {{n}} : INT; END_VAR\n  {{n}} := 1;\nEND_FUNCTION_BLOCK\n" + main,
        "global": main + config.format(**{**names, "glob": "VAR_GLOBAL {n} : INT; END_VAR\n  "}),
        "field": f"TYPE {p}_s : STRUCT {{n}} : INT; END_STRUCT; END_TYPE\n" + main,
        "enumerated value": f"TYPE {p}_e : ({p}_a, {{n}}); END_TYPE\n" + main,
        "task": main + config.format(**{**names, "task": "{n}"}),
        "program instance": main + config.format(**{**names, "inst": "{n}"}),
        "resource": main + config.format(**{**names, "res": "{n}"}),
        "configuration": main + config.format(**{**names, "cfg": "{n}"}),
    }
    return places, main, config, names
