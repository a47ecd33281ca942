"""The MatIEC backend: MatIEC's iec2c turns the ST into C (tool.py), whose layout becomes the manifest
and plc_tables.c (layout.py, with st_decls.py reading what iec2c's C loses from the sources); the FOR
semantics of the installed iec2c are measured (for_semantics.py) and the loops they change reported
(for_loops.py). backend.py is what the build driver sees (toolchain/backend.py's protocol).
"""

from .tool import DEFAULT_TIMEOUT_S, TIMEOUT_ENV, Matiec, MatiecError, find, flags, timeout_s, version

__all__ = ["DEFAULT_TIMEOUT_S", "TIMEOUT_ENV", "Matiec", "MatiecError", "find", "flags", "timeout_s", "version"]
