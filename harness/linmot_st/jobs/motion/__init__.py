"""The motion job (`linmot-st motion`): commission emulated drives from a PVL file with plc_project, then run
its motion program on every axis (power, home, move, the commissioned curves, a command-table entry, stop),
check each step against the PVL as written, and report (docs/motion.md)."""
