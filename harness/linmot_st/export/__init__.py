"""The ST library for other PLC tools: one expanded ST file, or PLCopen XML (TC6 2.01). See docs/import.md.

    from linmot_st.export import export_st, export_plcopen, ExportError
    export_st().text                       # st_lib/linmot.st with its includes expanded, as one ST text
    xml_bytes, lib = export_plcopen()      # the same library as PLCopen XML
"""

from .library import ExportError, Library, read_library
from .plcopen import export_plcopen, validate
from .st import export_st

__all__ = ["ExportError", "Library", "read_library", "export_st", "export_plcopen", "validate"]
