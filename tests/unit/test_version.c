/* SPDX-License-Identifier: BSD-3-Clause */
/* The version: the library's string equals the header's, and the number agrees with the parts. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "cyl/version.h"

static void test_version_agrees(void **state)
{
    char buf[32];
    (void)state;
    assert_string_equal(cyl_version(), CYL_VERSION_STRING);
    snprintf(buf, sizeof buf, "%d.%d.%d", CYL_VERSION_MAJOR, CYL_VERSION_MINOR, CYL_VERSION_PATCH);
    assert_string_equal(buf, CYL_VERSION_STRING);
    assert_int_equal(CYL_VERSION_NUMBER, CYL_VERSION_MAJOR * 10000 + CYL_VERSION_MINOR * 100 + CYL_VERSION_PATCH);
#if CYL_VERSION_NUMBER < 200
#error "CYL_VERSION_NUMBER must be usable in #if"
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_version_agrees)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
