"""The UPIDs the emulated drive's Motion Control SW reads (parameters, RAM values) and publishes (variables).

One table for the drive model and the harness. docs/upids.md lists every UPID with its meaning and source:
[MC] = LinMot "Motion Control SW" manual (SG5, E1100/E1200/E1400 UPIDs, its section numbers), [S004] = seed 004,
[CO1100] = the CANopen manual; INVENTED where no source names one (then a number no source uses).
"""

# parameters the MC reads (RAM values)
P_LAG_ALWAYS_WARN, P_LAG_ALWAYS_ERROR = 0x1472, 0x1473      # error 1473h: [MC] 10 (error 0Bh); warn INVENTED
P_LAG_STANDING_WARN, P_LAG_STANDING_ERROR = 0x1474, 0x1475  # error 1475h: [MC] 10 (error 0Ch); warn INVENTED
P_PREDEF_VMAX, P_PREDEF_ACC, P_PREDEF_DEC = 0x14BE, 0x14BF, 0x14C0   # [MC] 4.3.70
P_JOG_VELOCITY, P_JOG_INCREMENT = 0x14B0, 0x14B1                     # INVENTED
P_SCALE_POS, P_SCALE_VEL, P_SCALE_ACC = 0x14C8, 0x14C9, 0x14CA       # INVENTED (16-bit interface scaling)
P_CURVE_OFFSET, P_CURVE_TIME_SCALE, P_CURVE_AMPLITUDE = 0x14D0, 0x14D1, 0x14D2   # INVENTED
P_HOMING_MODE, P_INITIAL_POSITION = 0x1500, 0x1502                   # INVENTED
P_HOME_POSITION = 0x13C7                                             # [MC] 4.3.7 (009xh writes it)
P_HOMING_VMAX, P_HOMING_ACC = 0x1503, 0x1504                         # INVENTED
P_GO_TO_POSITION = 0x1510                                            # INVENTED
P_CLEARANCE_1, P_CLEARANCE_2 = 0x1520, 0x1521                        # INVENTED
P_QUICK_STOP_DEC = 0x1530                                            # INVENTED
P_LIMIT_POSITIVE, P_LIMIT_NEGATIVE = 0x146F, 0x146E                  # max / min position: [MC] 10 (errors 08h/07h)
P_LIMITS_ENABLE = 0x1602                                             # INVENTED
P_CW_COPY_MASK, P_CW_FORCE_MASK, P_CW_FORCE_VALUES = 0x1700, 0x1701, 0x1702   # INVENTED
P_RANGE1_UPID, P_RANGE1_MIN, P_RANGE1_MAX = 0x1780, 0x1781, 0x1782   # INVENTED (1710h is [MC] 7.2.2's fall delay)
P_ACTIVE_CONTROLLER_SET = 0x1393                                     # [MC] 4.3.5 (005xh writes it)
P_MAX_CURRENT_SET_A, P_MAX_CURRENT_SET_B = 0x13A6, 0x13BA            # [MC] 4.3.114..116, 7.2.1.2
P_STREAM_PERIOD = 0x14E6                                             # [MC] 4.3.40/41/43, 5.4
P_READY_TO_OPERATE_MODE = 0x6300                                     # [S004] 3.7, [MC] 3.7

# the variables the MC publishes (read by SDO as UPID RAM values, mapped into TxPDOs)
V_STATE_VAR, V_ACTUAL_POSITION, V_DEMAND_CURRENT = 0x1B62, 0x1B8D, 0x1B93      # [CO1100] default PDOs
V_DEMAND_POSITION_16, V_ACTUAL_POSITION_16 = 0x1B94, 0x1B95                    # [CO1100] default PDOs
V_STATUS_WORD, V_CONTROL_WORD, V_WARN_WORD, V_LOGGED_ERROR = 0x1D51, 0x1D52, 0x1D8E, 0x1D96   # [CO1100]
V_DEMAND_POSITION, V_TARGET_POSITION, V_POSITION_DIFFERENCE = 0x1B8C, 0x1B90, 0x1B91   # INVENTED
V_DEMAND_VELOCITY = 0x1BAE                                                     # INVENTED
V_ACTUAL_VELOCITY = 0x1BAF                                                     # public CANFuck PDO note
V_CT_VAR1, V_CT_VAR2 = 0x1E72, 0x1E73                                          # [MC] 4.3.124/125

# the master encoder and the encoder cams ([MC] 5.5, 7.3; docs/emulator.md "Master encoder and cams")
P_MASTER_ENCODER_SOURCE = 0x172A                                     # [MC] 7.3 (0 none, 1 X10, 2 X12)
P_MASTER_ENCODER_TYPE, P_MASTER_ENCODER_DECODING = 0x128E, 0x128F    # [MC] 7.3
P_MASTER_ENCODER_DIRECTION, P_MASTER_ENCODER_COUNTS_PER_REV = 0x1290, 0x1291   # [MC] 7.3
P_MASTER_ENCODER_SPEED_FILTER = 0x1293                               # [MC] 7.3
P_CAM_MODE, P_CAM_START_ENABLE = 0x1527, 0x1528                      # [MC] 5.5.1/5.5.2
P_CAM_MODULO_LENGTH = 0x1529                                         # INVENTED ([MC] 5.5.2 names no UPID)
P_TRIG_CAM_CURVE_RISE, P_TRIG_CAM_CURVE_FALL = 0x154A, 0x154B        # [MC] 4.3.63..68
P_TRIG_CAM_DELAY_RISE, P_TRIG_CAM_DELAY_FALL = 0x154C, 0x154D        # [MC] 4.3.63..68
V_CAM_ENABLED = 0x1BA9                                               # [MC] 5.5.2
V_MASTER_ENCODER_COUNTS, V_MASTER_ENCODER_SPEED = 0x1BA0, 0x1BA1     # INVENTED
P_WINDING_LEFT, P_WINDING_RIGHT, P_WINDING_PITCH = 0x1540, 0x1541, 0x1542    # INVENTED ([MC] gives headers only)
V_ACTUAL_FORCE = 0x1BFF                 # zylos146/CANFuck docs/a1100-pdo-config.md (actual force, 0.1 N)
# the drive's I/O (emulator/linmot/io.py) and the triggered commands (emulator/linmot/motion/triggered.py)
P_TRIGGER_MODE = 0x170C                                              # [MC] 7.2.2
P_TRIG_RISE_INHIBIT, P_TRIG_FALL_INHIBIT = 0x170D, 0x170E            # [MC] 7.2.2.2
P_TRIG_RISE_DELAY, P_TRIG_FALL_DELAY = 0x170F, 0x1710                # [MC] 7.2.2.3
P_BRAKE_OPERATION_ENABLED = 0x1717                                  # [MC] 7.2.1.1 (X4.3 brake: status word bit 0)
P_LIMIT_SWITCH_ERROR = 0x121B                                        # [MC] 7.2.3 (0 none, 1 power off, 2 quick stop)
P_ANALOG_POS_MIN, P_ANALOG_POS_MAX = 0x14DC, 0x14DD                  # INVENTED (019xh: position at X4.4 min / max)
P_TRIG_RISE_TARGET, P_TRIG_RISE_VMAX, P_TRIG_RISE_ACC, P_TRIG_RISE_DEC = 0x14F0, 0x14F1, 0x14F2, 0x14F3  # INVENTED
P_TRIG_FALL_TARGET, P_TRIG_FALL_VMAX, P_TRIG_FALL_ACC, P_TRIG_FALL_DEC = 0x14F4, 0x14F5, 0x14F6, 0x14F7  # INVENTED
V_CAPTURED_POSITION = 0x1E62                                         # [MC] 4.3.122/123
V_X4_INPUTS, V_X4_OUTPUTS, V_X6_OUTPUTS, V_ANALOG_X4_4 = 0x1DA0, 0x1DA1, 0x1DA2, 0x1DA3   # INVENTED
