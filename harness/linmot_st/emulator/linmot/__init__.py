"""The LinMot device of the emulated drives: the drive (E1100Drive, the B1100), its model and quirks, the
manufacturer objects, parameters, curves, command table, error log, I/O, master encoder, and motion/, the Motion
Control SW (docs/architecture.md section 4)."""
