/* SPDX-License-Identifier: Apache-2.0 */
/*
 * kt_gpio.c - GPIO port (libgpiod 1.6) against gpio-sim, run in the VM.
 *
 * The VM's /init makes one gpio-sim chip of 8 lines and exports its name in
 * $TRN_GPIO_CHIP and its simulated side in $TRN_GPIO_SIM
 * (/sys/devices/platform/gpio-sim.N/gpiochipM): sim_gpio<k>/value shows
 * what the port drives, writing pull-up/pull-down to sim_gpio<k>/pull
 * drives an input. Lines: 0 power, 1 trigger, 2 deployed (active high);
 * 3, 4, 5 the same active low.
 */
#include <fcntl.h>
#include <stdint.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ktest.h"
#include "trn_port/linux_gpio.h"

static const char *chip;
static const char *sim;

static int sim_read(unsigned line)
{
    char path[256];
    char c = '?';
    int fd;
    snprintf(path, sizeof path, "%s/sim_gpio%u/value", sim, line);
    fd = open(path, O_RDONLY);
    if (fd < 0) {
        return -1;
    }
    if (read(fd, &c, 1) != 1) {
        c = '?';
    }
    close(fd);
    return c == '1' ? 1 : c == '0' ? 0 : -1;
}

static int sim_pull(unsigned line, int up)
{
    char path[256];
    const char *v = up ? "pull-up" : "pull-down";
    int fd, ok;
    snprintf(path, sizeof path, "%s/sim_gpio%u/pull", sim, line);
    fd = open(path, O_WRONLY);
    if (fd < 0) {
        return -1;
    }
    ok = write(fd, v, strlen(v)) == (ssize_t)strlen(v);
    close(fd);
    return ok ? 0 : -1;
}

static trn_lgpio_cfg_t cfg_high(void)
{
    trn_lgpio_cfg_t c;
    trn_lgpio_cfg_default(&c);
    c.chip = chip;
    c.consumer = "trn-kt";
    c.power_offset = 0u;
    c.trigger_offset = 1u;
    c.deployed_offset = 2u;
    c.trigger_pulse_us = 100000u;
    return c;
}

static void power_enable_seen_on_sim(void)
{
    trn_lgpio_cfg_t c = cfg_high();
    trn_lgpio_t g;
    KT_CHECK(sim_pull(0u, 1) == 0); /* released line would read 1 */
    KT_ST(trn_lgpio_open(&g, &c), TRN_OK);
    KT_CHECK(sim_read(0u) == 0); /* requested inactive at start-up */
    KT_CHECK(sim_read(1u) == 0);
    KT_ST(trn_lgpio_set_power(&g, 1), TRN_OK);
    KT_CHECK(sim_read(0u) == 1);
    KT_ST(trn_lgpio_set_power(&g, 0), TRN_OK);
    KT_CHECK(sim_read(0u) == 0);
    KT_ST(trn_lgpio_set_power(&g, 2), TRN_E_ARG);
    KT_ST(trn_lgpio_close(&g), TRN_OK);
    KT_ST(trn_lgpio_set_power(&g, 1), TRN_E_ARG); /* closed */
    KT_CHECK(sim_pull(0u, 0) == 0);
}

/* A child samples the simulated trigger line every millisecond while the
 * parent pulses it; it reports what it saw through its exit status:
 * 0 = rose and fell with a width of at least half the configured one. */
static void trigger_pulse_seen_on_sim(void)
{
    trn_lgpio_cfg_t c = cfg_high();
    trn_lgpio_t g;
    pid_t pid;
    int wst = 0;
    KT_ST(trn_lgpio_open(&g, &c), TRN_OK);
    pid = fork();
    if (pid == 0) {
        long long t0 = kt_now_ms(), rose = -1, fell = -1;
        while (kt_now_ms() - t0 < 5000 && fell < 0) {
            int v = sim_read(1u);
            if (v == 1 && rose < 0) {
                rose = kt_now_ms();
            } else if (v == 0 && rose >= 0) {
                fell = kt_now_ms();
            }
            kt_sleep_ms(1);
        }
        if (rose < 0) {
            _exit(1);
        }
        if (fell < 0) {
            _exit(2);
        }
        _exit(fell - rose >= 50 ? 0 : 3);
    }
    kt_sleep_ms(200);
    KT_ST(trn_lgpio_trigger(&g), TRN_OK);
    KT_CHECK(sim_read(1u) == 0);
    KT_CHECK(pid > 0 && waitpid(pid, &wst, 0) == pid && WIFEXITED(wst));
    if (WIFEXITED(wst) && WEXITSTATUS(wst) != 0) {
        printf("trigger monitor: %d (1 no rise, 2 no fall, 3 too short)\n", WEXITSTATUS(wst));
    }
    KT_CHECK(WIFEXITED(wst) && WEXITSTATUS(wst) == 0);
    trn_lgpio_close(&g);
}

static void deployed_edge_received(void)
{
    trn_lgpio_cfg_t c = cfg_high();
    trn_lgpio_t g;
    pid_t pid;
    int v = -1, wst = 0;
    KT_CHECK(sim_pull(2u, 0) == 0);
    KT_ST(trn_lgpio_open(&g, &c), TRN_OK);
    KT_ST(trn_lgpio_read_deployed(&g, &v), TRN_OK);
    KT_CHECK(v == 0);
    pid = fork();
    if (pid == 0) {
        kt_sleep_ms(150);
        _exit(sim_pull(2u, 1) == 0 ? 0 : 1);
    }
    KT_ST(trn_lgpio_wait_deployed(&g, 5000), TRN_OK);
    KT_ST(trn_lgpio_read_deployed(&g, &v), TRN_OK);
    KT_CHECK(v == 1);
    KT_CHECK(pid > 0 && waitpid(pid, &wst, 0) == pid && WIFEXITED(wst) && WEXITSTATUS(wst) == 0);
    /* already deployed: at once, even with no time to wait */
    KT_ST(trn_lgpio_wait_deployed(&g, 0), TRN_OK);
    KT_CHECK(sim_pull(2u, 0) == 0);
    trn_lgpio_close(&g);
}

static void deployed_timeout(void)
{
    trn_lgpio_cfg_t c = cfg_high();
    trn_lgpio_t g;
    long long t0;
    KT_CHECK(sim_pull(2u, 0) == 0);
    KT_ST(trn_lgpio_open(&g, &c), TRN_OK);
    t0 = kt_now_ms();
    KT_ST(trn_lgpio_wait_deployed(&g, 200), TRN_E_TIMEOUT);
    KT_CHECK(kt_now_ms() - t0 >= 200);
    /* a bounce before the call (up, down) is not a deployment */
    KT_CHECK(sim_pull(2u, 1) == 0);
    KT_CHECK(sim_pull(2u, 0) == 0);
    KT_ST(trn_lgpio_wait_deployed(&g, 100), TRN_E_TIMEOUT);
    KT_ST(trn_lgpio_wait_deployed(&g, -1), TRN_E_ARG);
    trn_lgpio_close(&g);
}

static void active_low_lines(void)
{
    trn_lgpio_cfg_t c = cfg_high();
    trn_lgpio_t g;
    int v = -1;
    c.power_offset = 3u;
    c.trigger_offset = 4u;
    c.deployed_offset = 5u;
    c.power_active_low = 1u;
    c.trigger_active_low = 1u;
    c.deployed_active_low = 1u;
    c.trigger_pulse_us = 1000u;
    KT_CHECK(sim_pull(5u, 1) == 0); /* high = not deployed */
    KT_ST(trn_lgpio_open(&g, &c), TRN_OK);
    KT_CHECK(sim_read(3u) == 1); /* power off = high */
    KT_CHECK(sim_read(4u) == 1);
    KT_ST(trn_lgpio_set_power(&g, 1), TRN_OK);
    KT_CHECK(sim_read(3u) == 0);
    KT_ST(trn_lgpio_trigger(&g), TRN_OK);
    KT_CHECK(sim_read(4u) == 1);
    KT_ST(trn_lgpio_read_deployed(&g, &v), TRN_OK);
    KT_CHECK(v == 0);
    KT_CHECK(sim_pull(5u, 0) == 0); /* low = deployed */
    KT_ST(trn_lgpio_wait_deployed(&g, 2000), TRN_OK);
    trn_lgpio_close(&g);
}

/* All lines are taken at open: a second user is refused there; after close
 * the lines are free again. A failed open leaves nothing requested. */
static void lines_requested_once(void)
{
    trn_lgpio_cfg_t c = cfg_high();
    trn_lgpio_cfg_t other = cfg_high();
    trn_lgpio_t g, h;
    KT_ST(trn_lgpio_open(&g, &c), TRN_OK);
    other.power_offset = 6u;
    other.trigger_offset = 7u; /* deployed (2) still overlaps */
    KT_ST(trn_lgpio_open(&h, &other), TRN_E_IO);
    KT_CHECK(h.chip == NULL);
    KT_ST(trn_lgpio_close(&g), TRN_OK);
    /* 6 and 7 were released by the failed open: usable now */
    KT_ST(trn_lgpio_open(&h, &other), TRN_OK);
    trn_lgpio_close(&h);
    KT_ST(trn_lgpio_open(&g, &c), TRN_OK);
    trn_lgpio_close(&g);
}

static void bad_chip_and_offsets(void)
{
    trn_lgpio_cfg_t c = cfg_high();
    trn_lgpio_t g;
    c.deployed_offset = 8u; /* the chip has 8 lines */
    KT_ST(trn_lgpio_open(&g, &c), TRN_E_RANGE);
    KT_CHECK(g.chip == NULL);
    c = cfg_high();
    c.chip = "nosuchchip";
    KT_ST(trn_lgpio_open(&g, &c), TRN_E_IO);
}

int main(void)
{
    chip = kt_env("TRN_GPIO_CHIP", "gpiochip0");
    sim = kt_env("TRN_GPIO_SIM", "/sys/devices/platform/gpio-sim.0/gpiochip0");
    KT_RUN(power_enable_seen_on_sim);
    KT_RUN(trigger_pulse_seen_on_sim);
    KT_RUN(deployed_edge_received);
    KT_RUN(deployed_timeout);
    KT_RUN(active_low_lines);
    KT_RUN(lines_requested_once);
    KT_RUN(bad_chip_and_offsets);
    return kt_finish("kt_gpio");
}
