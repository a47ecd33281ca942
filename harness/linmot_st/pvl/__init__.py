"""LinMot PVL ("Parameter Value List") files: parse, validate, write (docs/pvl.md).

    from linmot_st.pvl import load_pvl, parse_pvl, write_pvl, PvlError
"""

from .codec import CtEntryBlock, CurveInfo, decode_stringlets, encode_stringlets, stringlet_text
from .errors import Diagnostic, PvlError
from .layers import LAYERS, Layer, TreeIdentity
from .model import CommandTableEntry, Curve, Parameter, ParameterObject, PvlFile, Source, StringParameter
from .parser import load_pvl, parse_pvl
from .validate import validate
from .writer import save_pvl, write_pvl

__all__ = [
    "load_pvl", "parse_pvl", "write_pvl", "save_pvl", "validate", "PvlError", "Diagnostic",
    "PvlFile", "ParameterObject", "Parameter", "StringParameter", "Curve", "CommandTableEntry", "Source",
    "CurveInfo", "CtEntryBlock", "TreeIdentity", "Layer", "LAYERS",
    "decode_stringlets", "encode_stringlets", "stringlet_text",
]
