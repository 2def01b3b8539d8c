/* SPDX-License-Identifier: Apache-2.0 */
/* handcount.c - a tiny call chain whose stack depth is counted by hand from
 * the arm-none-eabi disassembly (tools/stack/test_trn_stack.py). Not part of
 * any library. noinline keeps the three frames separate; volatile arrays keep
 * the locals on the stack at -O2. */
#include <stdint.h>

int32_t hc_leaf(int32_t a);
int32_t hc_mid(int32_t a);
int32_t hc_top(int32_t a);

__attribute__((noinline)) int32_t hc_leaf(int32_t a)
{
    volatile int32_t buf[6];
    buf[0] = a;
    buf[5] = a + 1;
    return buf[0] + buf[5];
}

__attribute__((noinline)) int32_t hc_mid(int32_t a)
{
    volatile int32_t buf[10];
    buf[0] = hc_leaf(a);
    buf[9] = hc_leaf(a + 2);
    return buf[0] + buf[9];
}

int32_t hc_top(int32_t a)
{
    volatile int32_t x[2];
    x[0] = hc_mid(a);
    x[1] = hc_leaf(a);
    return x[0] + x[1];
}
