# SPDX-License-Identifier: BSD-3-Clause
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))          # slam_demo/ -> import cylslam
FIXTURES = os.path.join(HERE, "fixtures")
