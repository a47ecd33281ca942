"""The protocol catalogue: the numbers both ends of the protocol share (the PLC library and the emulated drive),
each in one place.

    commands/     the motion commands, one row each, one module per command group (commands/row.py: the row)
    words.py      the MC's main states, control/status/warn word bits, the error codes the MC raises
    codes.py      SDO abort codes, E1100 result codes
    errors.py     the library's ErrorIDs and the drive's error table
    upids.py      the UPIDs the MC reads and publishes
    generate.py   the ST and docs files generated from them: python -m linmot_st.protocol --write | --check
"""
