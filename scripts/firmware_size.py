#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""What a firmware keeps of libcyl (`make cross`): the text of a firmware image, of an empty main
linked the same way, and the part of the firmware's symbols that libcyl's objects define.

usage: firmware_size.py FIRMWARE.elf EMPTY.elf LIBCYL.a [CONFIGURATION]   (arm-none-eabi-size and -nm on PATH)
  CONFIGURATION  words naming libcyl's compile-time configuration, for the message (default "default")
"""
import subprocess
import sys


def text_bytes(elf):
    """The text column of arm-none-eabi-size (code and read-only data)."""
    out = subprocess.run(["arm-none-eabi-size", elf], capture_output=True, text=True, check=True).stdout
    return int(out.splitlines()[1].split()[0])


def main(argv):
    if len(argv) not in (4, 5):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    fw, empty, lib = argv[1:4]
    config = argv[4] if len(argv) == 5 else "default"
    nm = ["arm-none-eabi-nm"]
    defined = set()
    for line in subprocess.run(nm + ["--defined-only", lib], capture_output=True, text=True, check=True).stdout.splitlines():
        parts = line.split()
        if len(parts) == 3:
            defined.add(parts[2])
    own = 0
    for line in subprocess.run(nm + ["-S", fw], capture_output=True, text=True, check=True).stdout.splitlines():
        parts = line.split()   # address size type name
        if len(parts) == 4 and parts[2] in "tTrR" and parts[3] in defined:
            own += int(parts[1], 16)
    t_fw, t_empty = text_bytes(fw), text_bytes(empty)
    print(f"cross: a firmware that loads a table, segments and observes (libcyl/examples/firmware.c; libcyl's "
          f"{config} configuration) links {t_fw} B of text, {t_fw - t_empty} B more than an empty main; "
          f"{own} B of it libcyl's own")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
