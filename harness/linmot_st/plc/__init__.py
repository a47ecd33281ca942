"""Load a compiled PLC and run it scan by scan in virtual time (docs/architecture.md section 2)."""

from .access import PathError
from .faults import FAULT_KINDS, PlcFault
from .layout import LayoutError
from .runtime import IdleWatch, Plc
from .variable import Var

__all__ = ["Plc", "IdleWatch", "PlcFault", "PathError", "LayoutError", "Var", "FAULT_KINDS"]
