/* stream.c: a camera over a paged .clod streamed through a page pool, the host doing the
 * I/O.
 *
 * usage: stream FILE.clod [FRAMES [POOL_SLOTS]]
 *
 * Reads the file's root only and makes a pool of POOL_SLOTS slots (default: a quarter of the
 * streamed pages). Each frame a camera, orbiting the model and moving in and out, refines
 * over the streamed file: splits whose pages are absent wait and their pages go into the
 * frame's lists. The lists go to the pool, which says which pages to load into which slots;
 * the host reads them with fseek and fread and hands them back, and the pool checks each
 * one. A page that fails is reported once and stays absent; the frames go on. When the pool
 * is too small for what the camera wants, a pressure scales its tolerance up, so it leaves
 * pages to be evicted for the ones it wants now. Beside the pool, a device vertex pool
 * (kept here in host memory, as a renderer keeps its vertex buffer) receives the root
 * pages' vertices once and each installed page's in its slot; every index the camera
 * emits must name a vertex copied there. Prints one JSON line with the totals. */

#include "caveclod.h"

#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define WANTS 256
#define PI 3.14159265f
#define VERTEX_BYTES 32
#define MAX_POLYGONS 20000

/* Copies `install`'s vertices into the device pool `device`, after marking its slot's
 * `slot_vertices` places unwritten (0xff bytes) when it is a page's. */
static void copy_install(unsigned char *device, const CaveclodVertexInstall *install,
                         uint32_t slot_vertices) {
    unsigned char *at = device + (size_t)install->first * VERTEX_BYTES;
    if (slot_vertices > 0) {
        memset(at, 0xff, (size_t)slot_vertices * VERTEX_BYTES);
    }
    memcpy(at, install->vertices, (size_t)install->count * VERTEX_BYTES);
}

/* Whether device vertex `i` of `count` was written by a copy. */
static int written(const unsigned char *device, uint32_t count, uint32_t i) {
    static const unsigned char unwritten[VERTEX_BYTES] = {
        0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
        0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
        0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff};
    return i < count && memcmp(device + (size_t)i * VERTEX_BYTES, unwritten, VERTEX_BYTES) != 0;
}

static int fail(const char *what, CaveclodStatus status) {
    printf("{\"error\": \"%s\", \"status\": %d, \"message\": \"%s\"}\n", what, (int)status,
           caveclod_status_message((int32_t)status));
    return 1;
}

/* `len` bytes on a 64-byte boundary, from a block `*owner` to free. */
static void *aligned(size_t len, void **owner) {
    unsigned char *block = malloc(len + 64);
    *owner = block;
    return block == NULL ? NULL : block + (64 - (size_t)((uintptr_t)block % 64)) % 64;
}

/* Frame `frame` of an orbit round the box `lo`..`hi`, from over twice its size away in to
 * a fifth, where most of the model is out of view. */
static CaveclodView orbit(const float lo[3], const float hi[3], unsigned long frame) {
    CaveclodView v;
    float c[3], size = 0.0f, a = (float)frame * 0.03f, r;
    int k;
    for (k = 0; k < 3; ++k) {
        c[k] = 0.5f * (lo[k] + hi[k]);
        size = fmaxf(size, hi[k] - lo[k]);
    }
    r = size * (1.3f + 1.1f * cosf(a * 0.7f));
    v.eye[0] = c[0] + r * cosf(a);
    v.eye[1] = c[1] + 0.3f * r;
    v.eye[2] = c[2] + r * sinf(a);
    memcpy(v.target, c, sizeof c);
    v.up[0] = 0.0f;
    v.up[1] = 1.0f;
    v.up[2] = 0.0f;
    v.fov_y = PI / 3.0f;
    v.aspect = 1280.0f / 720.0f;
    v.near = size * 0.001f;
    v.far = size * 100.0f;
    v.viewport_height = 720;
    return v;
}

/* The file's root (its header's `file_len` first bytes), 64-byte aligned. */
static void *read_root(FILE *f, size_t *len, void **owner) {
    unsigned char header[64];
    uint64_t root_len;
    void *bytes;
    if (fread(header, 1, sizeof header, f) != sizeof header) {
        return NULL;
    }
    memcpy(&root_len, header + 16, sizeof root_len);
    bytes = aligned((size_t)root_len, owner);
    if (bytes == NULL || fseek(f, 0, SEEK_SET) != 0 || fread(bytes, 1, root_len, f) != root_len) {
        return NULL;
    }
    *len = (size_t)root_len;
    return bytes;
}

int main(int argc, char **argv) {
    CaveclodPagedRoot root;
    CaveclodPagedCounts counts;
    CaveclodPoolConfig config;
    CaveclodPool pool;
    CaveclodLoadRequest loads[16];
    CaveclodPageKey evicted[16];
    CaveclodScheduleStats stats;
    CaveclodPageFault fault;
    CaveclodPageInfo top;
    CaveclodFrameLists lists;
    CaveclodStreamedFile streamed_file;
    CaveclodCameraConfig camera_config;
    CaveclodCamera cam;
    CaveclodRefineStats rs;
    CaveclodRefineParams params;
    CaveclodPressure pressure;
    float scale = 1.0f, max_scale = 1.0f;
    CaveclodStreamedReads reads;
    CaveclodVertexInstall install;
    CaveclodView view;
    CaveclodStatus s;
    FILE *f;
    void *root_bytes, *memory, *pool_bytes, *lists_memory, *camera_memory;
    void *root_block = NULL, *memory_block, *pool_block, *lists_block, *camera_block;
    size_t root_len = 0, memory_len = 0, lists_len = 0, camera_len = 0;
    unsigned long frames = 200, installs = 0, evictions = 0, faults = 0, deferred = 0, frame;
    unsigned long polygons = 0, vertex_installs = 0, stale_indices = 0;
    unsigned char *device;
    uint32_t *indices, *offsets;
    size_t total, k;
    uint32_t file, i, streamed, waited;

    if (argc < 2 || argc > 4) {
        fprintf(stderr, "usage: stream FILE.clod [FRAMES [POOL_SLOTS]]\n");
        return 2;
    }
    if (argc > 2) {
        frames = strtoul(argv[2], NULL, 10);
    }
    f = fopen(argv[1], "rb");
    if (f == NULL || (root_bytes = read_root(f, &root_len, &root_block)) == NULL) {
        fprintf(stderr, "%s: cannot read its root\n", argv[1]);
        return 1;
    }
    if ((s = caveclod_paged_root_open(root_bytes, root_len, &root)) != CAVECLOD_STATUS_OK) {
        return fail("caveclod_paged_root_open", s);
    }
    caveclod_paged_root_counts(&root, &counts);
    streamed = counts.pages - counts.root_pages;

    /* The pool: slots the size of the largest page, a quarter of the streamed pages. */
    config.slot_bytes = (counts.largest_page + 63) / 64 * 64;
    config.slots = argc > 3 ? (uint32_t)strtoul(argv[3], NULL, 10) : streamed / 4 + 1;
    config.files = 1;
    config.pages = counts.pages;
    config.max_requests = 1024;
    /* The device vertex pool: a slot's place per slot, then the root pages' vertices. */
    config.slot_vertices = counts.most_page_vertices;
    config.vertex_pool_vertices = config.slots * config.slot_vertices + counts.root_vertices;
    if ((s = caveclod_pool_memory_size(&config, &memory_len)) != CAVECLOD_STATUS_OK) {
        return fail("caveclod_pool_memory_size", s);
    }
    memory = aligned(memory_len, &memory_block);
    pool_bytes = aligned((size_t)config.slots * config.slot_bytes, &pool_block);
    s = caveclod_pool_init(&config, memory, memory_len, pool_bytes,
                           (size_t)config.slots * config.slot_bytes, &pool);
    if (s != CAVECLOD_STATUS_OK) {
        return fail("caveclod_pool_init", s);
    }
    if ((s = caveclod_pool_add_file(&pool, &root, &file)) != CAVECLOD_STATUS_OK) {
        return fail("caveclod_pool_add_file", s);
    }
    device = malloc((size_t)config.vertex_pool_vertices * VERTEX_BYTES);
    indices = malloc(3 * sizeof *indices * MAX_POLYGONS);
    offsets = malloc(sizeof *offsets * (counts.surfaces + 1));
    if (device == NULL || indices == NULL || offsets == NULL) {
        return fail("malloc", CAVECLOD_STATUS_MEMORY_TOO_SMALL);
    }
    memset(device, 0xff, (size_t)config.vertex_pool_vertices * VERTEX_BYTES);
    for (i = 0; i < counts.root_pages; ++i) {
        if ((s = caveclod_pool_root_vertices(&pool, &root, file, i, &install)) != CAVECLOD_STATUS_OK) {
            return fail("caveclod_pool_root_vertices", s);
        }
        copy_install(device, &install, 0);
    }

    /* The frame's lists, and a camera of at most MAX_POLYGONS polygons over the streamed
     * file. */
    if ((s = caveclod_frame_lists_memory_size(&pool, WANTS, &lists_len)) != CAVECLOD_STATUS_OK) {
        return fail("caveclod_frame_lists_memory_size", s);
    }
    lists_memory = aligned(lists_len, &lists_block);
    s = caveclod_frame_lists_init(&pool, WANTS, lists_memory, lists_len, &lists);
    if (s != CAVECLOD_STATUS_OK) {
        return fail("caveclod_frame_lists_init", s);
    }
    streamed_file.root = &root;
    streamed_file.pool = &pool;
    streamed_file.file = file;
    streamed_file.lists = &lists;
    caveclod_camera_config_polygon_budget_streamed(&streamed_file, MAX_POLYGONS, &camera_config);
    s = caveclod_camera_memory_size_streamed(&streamed_file, &camera_config, &camera_len);
    if (s != CAVECLOD_STATUS_OK) {
        return fail("caveclod_camera_memory_size_streamed", s);
    }
    camera_memory = aligned(camera_len, &camera_block);
    s = caveclod_camera_init_streamed(&streamed_file, &camera_config, camera_memory, camera_len,
                                      &cam);
    if (s != CAVECLOD_STATUS_OK) {
        return fail("caveclod_camera_init_streamed", s);
    }
    caveclod_paged_root_page(&root, 0, &top);
    caveclod_pressure_init(16.0f, &pressure);

    for (frame = 0; frame < frames; ++frame) {
        caveclod_pool_begin_frame(&pool);
        /* The camera refines over what is resident; what it waits for goes into the lists. */
        view = orbit(top.bounds_min, top.bounds_max, frame);
        caveclod_refine_params_default(&params);
        params.tolerance_px *= scale;
        s = caveclod_camera_refine_streamed(&cam, &streamed_file, &view, &params, &rs, &waited);
        if (s != CAVECLOD_STATUS_OK) {
            return fail("caveclod_camera_refine_streamed", s);
        }
        deferred += waited;
        polygons = rs.active_polygons;
        /* Its indices name the device pool's vertices: each must have been copied there. */
        s = caveclod_camera_emit_packed_streamed(&cam, &streamed_file, indices, 3 * MAX_POLYGONS,
                                                 offsets, counts.surfaces + 1, false, &total);
        if (s != CAVECLOD_STATUS_OK) {
            return fail("caveclod_camera_emit_packed_streamed", s);
        }
        for (k = 0; k < total; ++k) {
            stale_indices += !written(device, config.vertex_pool_vertices, indices[k]);
        }
        /* The lists go to the pool: wanted pages, and the pages the front stands on. */
        if ((s = caveclod_pool_apply(&pool, &lists)) != CAVECLOD_STATUS_OK) {
            return fail("caveclod_pool_apply", s);
        }
        /* "Load page P into slot S". */
        caveclod_pool_schedule(&pool, loads, 16, evicted, 16, &stats);
        evictions += stats.evictions;
        for (i = 0; i < stats.loads; ++i) {
            uint8_t *slot = NULL;
            size_t slot_len = 0;
            int read_ok;
            caveclod_pool_loading_slot(&pool, loads[i].slot, &slot, &slot_len);
            read_ok = slot_len >= loads[i].size && fseek(f, (long)loads[i].offset, SEEK_SET) == 0 &&
                      fread(slot, 1, loads[i].size, f) == loads[i].size;
            /* "Slot S holds these bytes", or "failed". */
            s = read_ok ? caveclod_pool_install(&pool, loads[i].slot, &root, &fault)
                        : (caveclod_pool_fail(&pool, loads[i].slot, &fault), CAVECLOD_STATUS_BAD_PAGE);
            if (s == CAVECLOD_STATUS_OK) {
                installs += 1;
                /* Its vertices go to its slot's place in the device pool. */
                s = caveclod_pool_page_vertices(&pool, loads[i].file, loads[i].page, &install);
                if (s != CAVECLOD_STATUS_OK) {
                    return fail("caveclod_pool_page_vertices", s);
                }
                copy_install(device, &install, config.slot_vertices);
                vertex_installs += 1;
            } else if (s == CAVECLOD_STATUS_BAD_PAGE) {
                faults += 1;
                fprintf(stderr, "%s: page %u: %s (kind %u)\n", argv[1], fault.page,
                        caveclod_status_message((int32_t)s), fault.kind);
            } else if (s == CAVECLOD_STATUS_PAGE_ABANDONED) {
                /* A parent loaded in this frame failed: the page stays absent, unreported. */
            } else {
                return fail("caveclod_pool_install", s);
            }
        }
        /* A full pool, or splits piling up while the reads fall behind, coarsen the camera. */
        caveclod_pressure_update(&pressure, &pool, &stats, waited, rs.active_nodes, &scale);
        max_scale = scale > max_scale ? scale : max_scale;
    }
    caveclod_frame_lists_reads(&lists, &reads);
    printf("{\"frames\": %lu, \"pages\": %u, \"slots\": %u, \"installs\": %lu, "
           "\"evictions\": %lu, \"faults\": %lu, \"deferred\": %lu, \"polygons\": %lu, "
           "\"absent_reads\": %llu, \"max_scale\": %.2f, \"vertex_installs\": %lu, "
           "\"stale_indices\": %lu}\n",
           frames, counts.pages, config.slots, installs, evictions, faults, deferred, polygons,
           (unsigned long long)reads.absent_reads, (double)max_scale, vertex_installs,
           stale_indices);
    fclose(f);
    free(offsets);
    free(indices);
    free(device);
    free(camera_block);
    free(lists_block);
    free(pool_block);
    free(memory_block);
    free(root_block);
    return 0;
}
