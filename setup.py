# SPDX-License-Identifier: BSD-3-Clause
"""Build of the `cyl` extension (cffi, python/cyl/_build.py) and the package layout; metadata is
in pyproject.toml. The version is read from libcyl's header, where it is written once."""
import re

from setuptools import setup

with open("libcyl/include/cyl/version.h") as f:
    VERSION = re.search(r'#define CYL_VERSION_STRING "([^"]+)"', f.read()).group(1)

setup(
    version=VERSION,
    packages=["cyl", "cylslam"],
    package_dir={"cyl": "python/cyl", "cylslam": "slam_demo/cylslam"},
    package_data={"cylslam": ["models/*.json"]},
    cffi_modules=["python/cyl/_build.py:ffibuilder"],
    zip_safe=False,
)
