#!/usr/bin/env bash
# Run a 32-bit ARM (armhf) Linux program under qemu user-mode emulation.
exec qemu-arm -L /usr/arm-linux-gnueabihf "$@"
