"""Suite-wide pytest setup: the `socketcan` tests run on a real SocketCAN stack (linmot_st_vcan.pytest_plugin)."""

pytest_plugins = ["linmot_st_vcan.pytest_plugin", "pytester"]
