/* SPDX-License-Identifier: Apache-2.0 */
/*
 * linux_gpio_cfg.c - the GPIO configuration's default and check
 * (port/include/trn_port/linux_gpio.h), the same for both libgpiod ports
 * (linux_gpio.c for 1.6, linux_gpio_v2.c for 2.x), built with either.
 */
#include "trn_port/linux_gpio.h"

#include <string.h>

static int is_flag(uint8_t v) { return v == 0u || v == 1u; }

trn_status_t trn_lgpio_cfg_default(trn_lgpio_cfg_t *cfg)
{
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->chip = "gpiochip0";
    cfg->consumer = "trn";
    cfg->power_offset = 0u;
    cfg->trigger_offset = 1u;
    cfg->deployed_offset = 2u;
    cfg->power_active_low = 0u;
    cfg->trigger_active_low = 0u;
    cfg->deployed_active_low = 0u;
    cfg->trigger_pulse_us = 1000u;
    return TRN_OK;
}

trn_status_t trn_lgpio_cfg_check(const trn_lgpio_cfg_t *cfg)
{
    if (cfg == NULL || cfg->chip == NULL || cfg->consumer == NULL) {
        return TRN_E_NULL;
    }
    if (cfg->chip[0] == '\0' || cfg->consumer[0] == '\0') {
        return TRN_E_SIZE;
    }
    if (cfg->power_offset > TRN_LGPIO_MAX_OFFSET || cfg->trigger_offset > TRN_LGPIO_MAX_OFFSET ||
        cfg->deployed_offset > TRN_LGPIO_MAX_OFFSET) {
        return TRN_E_ARG;
    }
    if (cfg->power_offset == cfg->trigger_offset || cfg->power_offset == cfg->deployed_offset ||
        cfg->trigger_offset == cfg->deployed_offset) {
        return TRN_E_ARG;
    }
    if (!is_flag(cfg->power_active_low) || !is_flag(cfg->trigger_active_low) ||
        !is_flag(cfg->deployed_active_low)) {
        return TRN_E_ARG;
    }
    if (cfg->trigger_pulse_us == 0u || cfg->trigger_pulse_us > TRN_LGPIO_MAX_PULSE_US) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}
