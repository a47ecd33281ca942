"""Packaging beyond pyproject.toml: a wheel carries st_lib/, plc_project/ and the project template
(examples/user_project, which `linmot-st init` copies) inside linmot_st/.

The two trees stay at the repository root (where the project's layout and every include path put them);
build_py copies them into the built package, so an installed linmot-st finds them beside its code
(linmot_st.resources). An editable install needs no copy: it reads them from the checkout. The sdist gets
them from MANIFEST.in.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
TREES = ("st_lib", "plc_project", "examples/user_project")   # linmot_st.resources: TREES, PROJECT_TEMPLATE


IGNORED = ("__pycache__", "*.pyc", "build", ".pytest_cache", ".cache", "plc-tests.xml")   # what a run leaves


class BuildPyWithLibrary(build_py):
    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        for tree in TREES:
            target = Path(self.build_lib) / "linmot_st" / tree
            shutil.rmtree(target, ignore_errors=True)
            shutil.copytree(ROOT / tree, target, ignore=shutil.ignore_patterns(*IGNORED))


setup(cmdclass={"build_py": BuildPyWithLibrary})
