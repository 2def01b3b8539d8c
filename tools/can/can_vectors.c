/* SPDX-License-Identifier: Apache-2.0 */
/* can_vectors.c - print test vectors of the C message encoders as JSON, for
 * the cantools cross-check (tools/can/check_dbc.py, CTest `can_dbc_cantools`).
 *
 *   trn_can_vectors > vectors.json
 *
 * One object per vector: message name, frame ID, DLC, the frame bytes the C
 * encoder produced (hex) and every DBC signal's raw integer taken from the C
 * message struct. Vectors: each field at its limits, then seeded random ones. */
#include <stdio.h>
#include <string.h>

#include "rng.h"
#include "trn_port/can_msg.h"
#include "trn_port/isotp.h"

static int g_first = 1;

static void begin(const char *name, const trn_can_frame_t *f)
{
    unsigned i;
    printf("%s\n  {\"msg\": \"%s\", \"id\": %u, \"dlc\": %u, \"data\": \"", g_first ? "" : ",",
           name, (unsigned)f->id, (unsigned)f->dlc);
    for (i = 0; i < f->dlc; ++i) {
        printf("%02x", f->data[i]);
    }
    printf("\", \"raw\": {");
    g_first = 0;
}

static void sig(const char *name, long v, int last)
{
    printf("\"%s\": %ld%s", name, v, last ? "}}" : ", ");
}

static int mast_cmd(const trn_mast_cmd_t *m)
{
    trn_can_frame_t f;
    if (trn_can_mast_cmd_encode(m, &f) != TRN_OK) {
        return 1;
    }
    begin("MAST_CMD", &f);
    sig("pan_cmd", m->pan_100urad, 0);
    sig("tilt_cmd", m->tilt_100urad, 0);
    sig("rate_max", m->rate_100urad_s, 0);
    sig("seq", m->seq, 0);
    sig("mode", m->mode, 1);
    return 0;
}

static int mast_status(const trn_mast_status_t *m)
{
    static const char *const st[6] = {"moving",       "pan_lim_min",  "pan_lim_max",
                                      "tilt_lim_min", "tilt_lim_max", "in_position"};
    static const char *const fl[6] = {"flt_pan_stall",   "flt_tilt_stall", "flt_encoder",
                                      "flt_overcurrent", "flt_overtemp",   "flt_cmd_invalid"};
    trn_can_frame_t f;
    int b;
    if (trn_can_mast_status_encode(m, &f) != TRN_OK) {
        return 1;
    }
    begin("MAST_STATUS", &f);
    sig("pan", m->pan_100urad, 0);
    sig("tilt", m->tilt_100urad, 0);
    for (b = 0; b < 6; ++b) {
        sig(st[b], (m->state >> b) & 1, 0);
    }
    for (b = 0; b < 6; ++b) {
        sig(fl[b], (m->faults >> b) & 1, 0);
    }
    sig("cmd_seq_ack", m->cmd_seq_ack, 0);
    sig("counter", m->counter, 1);
    return 0;
}

static int capture_cmd(const trn_capture_cmd_t *m)
{
    trn_can_frame_t f;
    if (trn_can_capture_cmd_encode(m, &f) != TRN_OK) {
        return 1;
    }
    begin("CAPTURE_CMD", &f);
    sig("capture_id", m->capture_id, 0);
    sig("max_points", m->max_points, 1);
    return 0;
}

static int heartbeat(uint32_t id, const trn_heartbeat_t *m)
{
    trn_can_frame_t f;
    if (trn_can_heartbeat_encode(id, m, &f) != TRN_OK) {
        return 1;
    }
    begin(id == TRN_CAN_ID_MAST_HB ? "MAST_HB" : "STEREO_HB", &f);
    sig("state", m->state, 0);
    sig("counter", m->counter, 0);
    sig("uptime", m->uptime_s, 1);
    return 0;
}

static int flow_control(uint8_t fs, uint8_t bs, uint8_t stmin)
{
    trn_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = TRN_CAN_ID_CAPTURE_FC;
    if (trn_isotp_encode_fc(fs, bs, stmin, f.data, &f.dlc) != TRN_OK) {
        return 1;
    }
    begin("CAPTURE_FC", &f);
    sig("flow_status", fs, 0);
    sig("pci_type", 3, 0);
    sig("block_size", bs, 0);
    sig("st_min", stmin, 1);
    return 0;
}

int main(int argc, char **argv)
{
    trn_rng_t r;
    int i, bad = 0;
    (void)argv;
    if (argc > 1) {
        fprintf(stderr, "usage: trn_can_vectors > vectors.json\n");
        return 2;
    }
    printf("[");
    /* limits */
    {
        const trn_mast_cmd_t c[3] = {
            {-32768, -32768, 0, 0, 0}, {32767, 32767, 65535, 255, 2}, {-1, 1, 1, 1, 1}};
        const trn_mast_status_t s[3] = {{-32768, 32767, 0, 0, 0, 0},
                                        {32767, -32768, 0x3F, 0x3F, 255, 255},
                                        {-1, 0, 0x15, 0x2A, 1, 128}};
        const trn_capture_cmd_t k[2] = {{0, 0}, {65535, 65535}};
        const trn_heartbeat_t h[2] = {{0, 0, 0}, {3, 255, 65535}};
        for (i = 0; i < 3; ++i) {
            bad |= mast_cmd(&c[i]) | mast_status(&s[i]);
        }
        for (i = 0; i < 2; ++i) {
            bad |= capture_cmd(&k[i]);
            bad |= heartbeat(TRN_CAN_ID_MAST_HB, &h[i]) | heartbeat(TRN_CAN_ID_STEREO_HB, &h[i]);
        }
        bad |= flow_control(0, 0, 0) | flow_control(1, 255, 0x7F) | flow_control(2, 8, 0xF9);
    }
    trn_rng_seed(&r, 2026);
    for (i = 0; i < 100; ++i) {
        trn_mast_cmd_t c = {(int16_t)trn_rng_int(&r, -32768, 32767),
                            (int16_t)trn_rng_int(&r, -32768, 32767),
                            (uint16_t)trn_rng_int(&r, 0, 65535), (uint8_t)trn_rng_int(&r, 0, 255),
                            (uint8_t)trn_rng_int(&r, 0, 2)};
        trn_mast_status_t s = {
            (int16_t)trn_rng_int(&r, -32768, 32767), (int16_t)trn_rng_int(&r, -32768, 32767),
            (uint8_t)trn_rng_int(&r, 0, 0x3F),       (uint8_t)trn_rng_int(&r, 0, 0x3F),
            (uint8_t)trn_rng_int(&r, 0, 255),        (uint8_t)trn_rng_int(&r, 0, 255)};
        trn_capture_cmd_t k = {(uint16_t)trn_rng_int(&r, 0, 65535),
                               (uint16_t)trn_rng_int(&r, 0, 65535)};
        trn_heartbeat_t h = {(uint8_t)trn_rng_int(&r, 0, 3), (uint8_t)trn_rng_int(&r, 0, 255),
                             (uint16_t)trn_rng_int(&r, 0, 65535)};
        bad |= mast_cmd(&c) | mast_status(&s) | capture_cmd(&k);
        bad |= heartbeat((i & 1) ? TRN_CAN_ID_MAST_HB : TRN_CAN_ID_STEREO_HB, &h);
        bad |= flow_control((uint8_t)trn_rng_int(&r, 0, 2), (uint8_t)trn_rng_int(&r, 0, 255),
                            (uint8_t)trn_rng_int(&r, 0, 255));
    }
    printf("\n]\n");
    if (bad) {
        fprintf(stderr, "trn_can_vectors: an encoder refused a vector\n");
        return 1;
    }
    return 0;
}
