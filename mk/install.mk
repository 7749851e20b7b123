# SPDX-License-Identifier: BSD-3-Clause
# make install PREFIX=DIR (top Makefile): libcyl's headers, libcyl.a, libcyl.so, libcyl.pc and the
# CMake package. Tested by installing into a scratch prefix and building an out-of-tree program
# with pkg-config alone and with find_package(cyl) (shared and static).
TEST_EXTRA += lib
TEST_EXTRA_BINS += tests/install/test_install.sh
