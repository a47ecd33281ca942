"""linmot_st: compile, run and test the LinMot ST library against an emulated E1100 drive.

Subpackages, one concern each (docs/architecture.md):
  toolchain  ST -> C (MatIEC's iec2c or the builtin compiler) -> shared library, cached by content
  plc        load a compiled PLC, step it scan by scan in virtual time, typed access to its variables
  bus        deterministic simulated CAN bus in virtual time; adapters to python-can buses
  emulator   sans-I/O LinMot E1100 CANopen drive model
  cosim      couples a PLC's CAN mailbox to a bus, scan by scan
  pvl        LinMot PVL files: parse, validate, write, generate ST data
  commission the main job: commission drives from a PVL file and report
  export     the library as one ST file or as PLCopen XML
"""

__version__ = "0.1.0"
