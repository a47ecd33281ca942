"""The interface's units in the model's (pu = 0.1 um, pu/s, pu/s^2), for the MC's modules."""

VEL_RAW = 10.0       # 1E-6 m/s = 10 pu/s
ACC_RAW = 100.0      # 1E-5 m/s^2 = 100 pu/s^2
