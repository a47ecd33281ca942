"""The jobs the `linmot-st` command runs end to end: `commission/` (`linmot-st commission`) and `motion/`
(`linmot-st motion`, after commissioning). "motion" alone names the drive's Motion Control model
(`linmot_st.emulator.linmot.motion`) and the ST library's motion half (st_lib/motion/)."""
