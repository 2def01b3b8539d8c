/* SPDX-License-Identifier: Apache-2.0 */
/* test_abi.c - trn_abi_check / TRN_ABI_CHECK (trn/abi.h): this file and the
 * library share the default configuration, so every size agrees; each size
 * off by one is reported. (A consumer with another configuration:
 * tests/abi/.) */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "trn/trn.h"

static void test_same_configuration_agrees(void **state)
{
    (void)state;
    assert_int_equal(TRN_ABI_CHECK(), TRN_OK);
}

static void test_each_size_checked(void **state)
{
    const size_t k = sizeof(trn_kernels_t), l = sizeof(trn_lnp_table_t), p = sizeof(trn_pyramid_t),
                 m = sizeof(trn_map_t);
    (void)state;
    assert_int_equal(trn_abi_check(k, l, p, m), TRN_OK);
    assert_int_equal(trn_abi_check(k + 1u, l, p, m), TRN_E_SIZE);
    assert_int_equal(trn_abi_check(k, l - 1u, p, m), TRN_E_SIZE);
    assert_int_equal(trn_abi_check(k, l, p + 8u, m), TRN_E_SIZE);
    assert_int_equal(trn_abi_check(k, l, p, m - 8u), TRN_E_SIZE);
    assert_int_equal(trn_abi_check(0u, 0u, 0u, 0u), TRN_E_SIZE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_configuration_agrees),
        cmocka_unit_test(test_each_size_checked),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
