"""The numbers both ends of the protocol share (the PLC library and the emulated drive)."""
