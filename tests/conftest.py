"""Suite-wide pytest setup: the `socketcan` tests run on a real SocketCAN stack (linmot_st_vcan.pytest_plugin);
the fixtures tests of several folders share. A folder's own fixtures are in its conftest.py."""

import pytest

pytest_plugins = ["linmot_st_vcan.pytest_plugin", "pytester"]


@pytest.fixture(scope="session")
def station():
    """The example station (examples/user_project, the project `linmot-st init` copies) built with the builtin
    compiler: the PLC of the rig tests (plctest/) and of the I/O clients (emulator/motion/)."""
    from linmot_st import resources
    from linmot_st.plctest.project import Project

    return Project(root=resources.CHECKOUT / "examples" / "user_project").build(backend="builtin")
