"""The ST library for other PLC tools: one expanded ST file, or PLCopen XML (TC6 2.01). See docs/import.md.

    from linmot_st.export import export_st, export_plcopen, ExportError
    export_st().text                       # st_lib/linmot.st with its includes expanded, as one ST text
    xml_bytes, lib = export_plcopen()      # the same library as PLCopen XML

The names are imported on first use, so that `linmot-st --help` does not load the compiler and lxml.
"""

from __future__ import annotations

import importlib

_WHERE = {"ExportError": "library", "Library": "library", "read_library": "library",
          "export_st": "st", "export_plcopen": "plcopen", "validate": "plcopen"}

__all__ = list(_WHERE)


def __getattr__(name: str):
    if name in _WHERE:
        return getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
