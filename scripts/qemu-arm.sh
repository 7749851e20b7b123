#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Run a 32-bit ARM (armhf) Linux program under qemu user-mode emulation.
exec qemu-arm -L /usr/arm-linux-gnueabihf "$@"
