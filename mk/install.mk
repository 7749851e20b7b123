# SPDX-License-Identifier: BSD-3-Clause
# make install PREFIX=DIR (top Makefile): libcyl's headers, libcyl.a and libcyl.pc. Tested by
# installing into a scratch prefix and building an out-of-tree program with pkg-config alone.
TEST_EXTRA += lib
TEST_EXTRA_BINS += tests/install/test_install.sh
