/* libFuzzer: the colour table loader. Any input must give a status, never a crash; a
 * table that loads must save back to the same bytes. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "cyl/colortable.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static cyl_colortable t;
    static uint8_t out[CYL_TABLE_FILE_SIZE];
    size_t len = 0;
    if (cyl_colortable_load(&t, data, size) != CYL_OK) return 0;
    if (size != CYL_TABLE_FILE_SIZE) abort();
    if (cyl_colortable_save(&t, out, sizeof out, &len) != CYL_OK || len != size) abort();
    if (memcmp(out, data, size) != 0) abort();
    return 0;
}
