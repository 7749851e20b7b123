#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Run a 64-bit ARM (AArch64) Linux program under qemu user-mode emulation.
exec qemu-aarch64 -L /usr/aarch64-linux-gnu "$@"
