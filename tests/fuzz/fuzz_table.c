/* SPDX-License-Identifier: BSD-3-Clause */
/* libFuzzer: the colour table loader (versions 1 and 2). Any input must give a status,
 * never a crash; a table that loads must save back to a file that loads to the same table,
 * byte-identical to the input when it saves in the input's version (a version-2 file whose
 * 3-D part is all ones saves as version 1).
 * The loader checks the CRC-32 (the last 4 bytes, over everything before them) before the
 * content, so random mutations almost never reach the content checks (class records, padding).
 * Each input is therefore also loaded a second time with its CRC recomputed (the first
 * bytes of the size its version field names, padded with zeros): that copy may only fail as
 * corrupt or of an unknown version, never on the checksum, and must round-trip when it loads. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "cyl/colortable.h"

static void check_loaded(const cyl_colortable *t, const uint8_t *data, size_t size)
{
    static uint8_t out[CYL_TABLE_FILE_MAX_SIZE];
    static cyl_colortable again;
    size_t len = 0;
    if (cyl_colortable_save(t, out, sizeof out, &len) != CYL_OK) abort();
    if (len == size && memcmp(out, data, size) != 0) abort();
    if (len != size && !(size == CYL_TABLE_FILE_SIZE_V2 && len == CYL_TABLE_FILE_SIZE)) abort();
    if (cyl_colortable_load(&again, out, len) != CYL_OK) abort();
    if (memcmp(&again, t, sizeof again) != 0) abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static cyl_colortable t;
    static uint8_t fixed[CYL_TABLE_FILE_MAX_SIZE];
    size_t fsize, crc_off;
    if (cyl_colortable_load(&t, data, size) == CYL_OK) check_loaded(&t, data, size);

    /* the same bytes with a valid CRC: the content checks */
    if (size < 8 || memcmp(data, "CYLT", 4) != 0) return 0;
    fsize = (data[4] | data[5] << 8) == CYL_TABLE_FILE_VERSION_V2 ? CYL_TABLE_FILE_SIZE_V2 : CYL_TABLE_FILE_SIZE;
    crc_off = fsize - 4u;
    memset(fixed, 0, sizeof fixed);
    memcpy(fixed, data, size < crc_off ? size : crc_off);
    uint32_t crc = cyl_crc32(0, fixed, crc_off);
    for (int i = 0; i < 4; i++) fixed[crc_off + (unsigned)i] = (uint8_t)(crc >> (8 * i));
    cyl_status s = cyl_colortable_load(&t, fixed, fsize);
    if (s == CYL_OK) check_loaded(&t, fixed, fsize);
    else if (s != CYL_ERR_FILE_CORRUPT && s != CYL_ERR_FILE_VERSION) abort();
    return 0;
}
