/* SPDX-License-Identifier: Apache-2.0 */
/* ref_chamfer.c - slow oracles for the chamfer transform (see ref_chamfer.h).
 * Written for obviousness, not speed: plain Dijkstra over the 26-neighbour
 * voxel graph, and a brute-force nearest-occupied-voxel search. */
#include "ref_chamfer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* Indexed binary min-heap of voxel indices keyed by d[], with decrease-key:
 * memory 12 bytes per voxel whatever the input. */
typedef struct {
    uint32_t *heap; /* voxel indices */
    uint32_t *pos;  /* pos[v]: place of v in heap, or NOT_IN_HEAP */
    uint32_t *d;    /* tentative distances */
    size_t n;       /* heap size */
} ref_heap_t;

#define NOT_IN_HEAP 0xFFFFFFFFu

static void heap_place(ref_heap_t *h, size_t i, uint32_t v)
{
    h->heap[i] = v;
    h->pos[v] = (uint32_t)i;
}

static void heap_up(ref_heap_t *h, size_t i)
{
    uint32_t v = h->heap[i];
    while (i > 0u) {
        size_t parent = (i - 1u) / 2u;
        if (h->d[h->heap[parent]] <= h->d[v]) {
            break;
        }
        heap_place(h, i, h->heap[parent]);
        i = parent;
    }
    heap_place(h, i, v);
}

static uint32_t heap_pop(ref_heap_t *h)
{
    uint32_t top = h->heap[0];
    uint32_t last = h->heap[--h->n];
    size_t i = 0u;
    h->pos[top] = NOT_IN_HEAP;
    if (h->n == 0u) {
        return top;
    }
    for (;;) {
        size_t c = 2u * i + 1u;
        if (c >= h->n) {
            break;
        }
        if (c + 1u < h->n && h->d[h->heap[c + 1u]] < h->d[h->heap[c]]) {
            c++;
        }
        if (h->d[last] <= h->d[h->heap[c]]) {
            break;
        }
        heap_place(h, i, h->heap[c]);
        i = c;
    }
    heap_place(h, i, last);
    return top;
}

void ref_chamfer3d_dijkstra(const uint8_t *occ, uint8_t *dist, int nx, int ny, int nz, unsigned cap)
{
    const size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    const uint32_t inf = 0xFFFFFFFFu;
    ref_heap_t h;
    size_t i;
    h.heap = malloc(n * sizeof *h.heap);
    h.pos = malloc(n * sizeof *h.pos);
    h.d = malloc(n * sizeof *h.d);
    h.n = 0u;
    if (h.heap == NULL || h.pos == NULL || h.d == NULL) {
        fprintf(stderr, "ref_chamfer3d_dijkstra: out of memory\n");
        abort();
    }
    for (i = 0u; i < n; i++) {
        h.pos[i] = NOT_IN_HEAP;
        h.d[i] = inf;
        if (occ[i] != 0u) {
            h.d[i] = 0u;
            heap_place(&h, h.n++, (uint32_t)i); /* all keys 0: already a heap */
        }
    }
    while (h.n > 0u) {
        uint32_t v = heap_pop(&h);
        int x = (int)(v % (uint32_t)nx);
        int y = (int)((v / (uint32_t)nx) % (uint32_t)ny);
        int z = (int)(v / ((uint32_t)nx * (uint32_t)ny));
        int ox, oy, oz;
        for (oz = -1; oz <= 1; oz++) {
            for (oy = -1; oy <= 1; oy++) {
                for (ox = -1; ox <= 1; ox++) {
                    int m = abs(ox) + abs(oy) + abs(oz); /* 1 face, 2 edge, 3 corner */
                    int qx = x + ox, qy = y + oy, qz = z + oz;
                    uint32_t q, nd;
                    if (m == 0 || qx < 0 || qy < 0 || qz < 0 || qx >= nx || qy >= ny || qz >= nz) {
                        continue;
                    }
                    q = ((uint32_t)qz * (uint32_t)ny + (uint32_t)qy) * (uint32_t)nx + (uint32_t)qx;
                    nd = h.d[v] + (m == 1 ? 3u : (m == 2 ? 4u : 5u));
                    if (nd < h.d[q]) {
                        /* Settled voxels never improve (non-negative weights). */
                        h.d[q] = nd;
                        if (h.pos[q] == NOT_IN_HEAP) {
                            h.heap[h.n] = q;
                            h.pos[q] = (uint32_t)h.n;
                            h.n++;
                        }
                        heap_up(&h, h.pos[q]);
                    }
                }
            }
        }
    }
    for (i = 0u; i < n; i++) {
        dist[i] = (uint8_t)(h.d[i] < cap ? h.d[i] : cap);
    }
    free(h.d);
    free(h.pos);
    free(h.heap);
}

double ref_euclid_nearest(const uint8_t *occ, int nx, int ny, int nz, int x, int y, int z)
{
    double best2 = -1.0;
    int qx, qy, qz;
    for (qz = 0; qz < nz; qz++) {
        for (qy = 0; qy < ny; qy++) {
            for (qx = 0; qx < nx; qx++) {
                size_t q = ((size_t)qz * (size_t)ny + (size_t)qy) * (size_t)nx + (size_t)qx;
                if (occ[q] != 0u) {
                    double dx = (double)(qx - x), dy = (double)(qy - y), dz = (double)(qz - z);
                    double d2 = dx * dx + dy * dy + dz * dz;
                    if (best2 < 0.0 || d2 < best2) {
                        best2 = d2;
                    }
                }
            }
        }
    }
    return best2 < 0.0 ? REF_EUCLID_NONE : sqrt(best2);
}
