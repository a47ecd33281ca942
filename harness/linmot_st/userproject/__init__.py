"""`linmot-st init DIR`: a new PLC project of the user's own, tested with pytest from the first minute.

The project is a copy of examples/user_project (the wheel carries it; linmot_st.resources finds it): a
station program using the library, its CONFIGURATION, a PVL slot with the dataset generated from it, tests
in Python and in ST, and CI files for GitHub Actions and GitLab. `cd DIR && pytest` passes with nothing but
linmot-st installed (and gcc).
"""
