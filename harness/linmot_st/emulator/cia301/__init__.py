"""The CiA 301 parts of the emulated drives: SDO server, standard objects 1000h..1FFFh, NMT/boot-up/heartbeat,
PDOs and SYNC, the EDS (docs/architecture.md section 4)."""
