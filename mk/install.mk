# SPDX-License-Identifier: BSD-3-Clause
# make install PREFIX=DIR (top Makefile): libcyl's headers, libcyl.a, libcyl.so, libcyl.pc and the
# CMake package (libcyl's own Makefile), then the tools into PREFIX/bin and the data they default
# to into PREFIX/share/cyl, where an installed tool finds them from any directory
# (frontend/include/cylfe/data_files.hpp; CYL_DATA_DIR overrides). `make -C libcyl install` installs
# the library alone (firmware and other C users). The tools' media plugin (image and video files,
# windows: frontend/include/cylfe/media.hpp) goes to PREFIX/lib/cyl. Tested by installing into a scratch prefix,
# building an out-of-tree program with pkg-config alone and with find_package(cyl) (shared and
# static), and running the installed tools from an unrelated directory.
INSTALL_TOOLS := cyl cyl-train cyl-score cyl-calibrate cyl-render cyl-synth-validate cyl_paper
INSTALL_DATA := $(sort $(wildcard calib_data/*.yaml calib_data/*.cylt))
TEST_EXTRA += lib $(INSTALL_TOOLS:%=$(BUILD)/%)
TEST_EXTRA_BINS += tests/install/test_install.sh
# it builds and installs without the sanitizers whatever the caller passes
SAN_SKIP += tests/install/test_install.sh

.PHONY: install-tools
install-tools: $(INSTALL_TOOLS:%=$(BUILD)/%) $(MEDIA_SO)
	install -d $(DESTDIR)$(or $(PREFIX),/usr/local)/bin $(DESTDIR)$(or $(PREFIX),/usr/local)/share/cyl \
	  $(DESTDIR)$(or $(PREFIX),/usr/local)/lib/cyl
	install -m 755 $(INSTALL_TOOLS:%=$(BUILD)/%) $(DESTDIR)$(or $(PREFIX),/usr/local)/bin/
	install -m 755 $(MEDIA_SO) $(DESTDIR)$(or $(PREFIX),/usr/local)/lib/cyl/
	install -m 644 $(INSTALL_DATA) $(DESTDIR)$(or $(PREFIX),/usr/local)/share/cyl/
