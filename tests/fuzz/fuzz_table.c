/* SPDX-License-Identifier: BSD-3-Clause */
/* libFuzzer: the colour table loader. Any input must give a status, never a crash; a
 * table that loads must save back to the same bytes.
 * The loader checks the CRC-32 (the last 4 bytes, over everything before them) before the
 * content, so random mutations almost never reach the content checks (class records, padding). Each input is therefore also loaded a second time with its
 * CRC recomputed (the first CYL_TABLE_FILE_SIZE bytes, padded with zeros): that copy may only
 * fail as corrupt, never on the checksum, and must round-trip when it loads. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "cyl/colortable.h"

#define CRC_OFFSET (CYL_TABLE_FILE_SIZE - 4u)

static void check_loaded(const cyl_colortable *t, const uint8_t *data, size_t size)
{
    static uint8_t out[CYL_TABLE_FILE_SIZE];
    size_t len = 0;
    if (size != CYL_TABLE_FILE_SIZE) abort();
    if (cyl_colortable_save(t, out, sizeof out, &len) != CYL_OK || len != size) abort();
    if (memcmp(out, data, size) != 0) abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static cyl_colortable t;
    static uint8_t fixed[CYL_TABLE_FILE_SIZE];
    if (cyl_colortable_load(&t, data, size) == CYL_OK) check_loaded(&t, data, size);

    /* the same bytes with a valid CRC: the content checks */
    if (size < 8 || memcmp(data, "CYLT", 4) != 0) return 0;
    memset(fixed, 0, sizeof fixed);
    memcpy(fixed, data, size < CRC_OFFSET ? size : CRC_OFFSET);
    uint32_t crc = cyl_crc32(0, fixed, CRC_OFFSET);
    for (int i = 0; i < 4; i++) fixed[CRC_OFFSET + (unsigned)i] = (uint8_t)(crc >> (8 * i));
    cyl_status s = cyl_colortable_load(&t, fixed, sizeof fixed);
    if (s == CYL_OK) check_loaded(&t, fixed, sizeof fixed);
    else if (s != CYL_ERR_FILE_CORRUPT && s != CYL_ERR_FILE_VERSION) abort();
    return 0;
}
