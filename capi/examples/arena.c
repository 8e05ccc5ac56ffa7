/* arena.c: the C interface of caveclod in fixed memory, as a console runtime runs it.
 *
 * usage: arena FILE.clod EX EY EZ TX TY TZ [POLYGON_BUDGET [ARENA_BYTES]]
 *
 * Every byte the runtime touches comes from one arena the program reserves at start (a
 * static buffer; ARENA_BYTES uses only its first bytes): the file's bytes, one camera with
 * a hard polygon budget (default 20000), and its index lists, each sized from the file's
 * counts and the budget. The view is refine.c's. Prints one JSON line with the counts and
 * the arena's use; a full arena is reported as a status (exit code 3), never a crash. */

#include "caveclod.h"

#include <stdio.h>
#include <stdlib.h>

#define ARENA_CAPACITY (64u << 20)
#define MAX_PASSES 1000

/* The one reservation: 8-byte words, so the arena's start is aligned for everything. */
static uint64_t arena_buffer[ARENA_CAPACITY / 8];

static int fail(const char *what, CaveclodStatus status, const CaveclodArena *arena) {
    printf("{\"error\": \"%s\", \"status\": %d, \"message\": \"%s\", \"arena_used\": %lu, "
           "\"arena_size\": %lu}\n",
           what, (int)status, caveclod_status_message((int32_t)status),
           (unsigned long)arena->used, (unsigned long)arena->size);
    return status == CAVECLOD_STATUS_ARENA_FULL ? 3 : 1;
}

int main(int argc, char **argv) {
    CaveclodArena arena;
    CaveclodHierarchy h;
    CaveclodHierarchyCounts hc;
    CaveclodCameraConfig config;
    CaveclodCamera cam;
    CaveclodCameraCounts cc;
    CaveclodRefineParams params;
    CaveclodRefineStats stats;
    CaveclodView view;
    CaveclodStatus s;
    FILE *f;
    long file_len;
    size_t camera_bytes = 0, index_room, total = 0;
    unsigned long budget = 20000, arena_bytes = ARENA_CAPACITY;
    void *file_bytes, *camera_memory, *indices, *offsets;
    int i, passes;

    if (argc < 8 || argc > 10) {
        fprintf(stderr, "usage: arena FILE.clod EX EY EZ TX TY TZ [POLYGON_BUDGET [ARENA_BYTES]]\n");
        return 2;
    }
    if (argc > 8) {
        budget = strtoul(argv[8], NULL, 10);
    }
    if (argc > 9 && strtoul(argv[9], NULL, 10) < ARENA_CAPACITY) {
        arena_bytes = strtoul(argv[9], NULL, 10);
    }
    caveclod_arena_init(&arena, arena_buffer, arena_bytes);

    /* The file, into the arena (aligned to 64: no record straddles cache lines). */
    f = fopen(argv[1], "rb");
    if (f == NULL || fseek(f, 0, SEEK_END) != 0 || (file_len = ftell(f)) < 0 ||
        fseek(f, 0, SEEK_SET) != 0) {
        fprintf(stderr, "arena: cannot read %s\n", argv[1]);
        return 1;
    }
    if ((s = caveclod_arena_alloc(&arena, (size_t)file_len, 64, &file_bytes)) != CAVECLOD_STATUS_OK) {
        fclose(f);
        return fail("file", s, &arena);
    }
    if (fread(file_bytes, 1, (size_t)file_len, f) != (size_t)file_len) {
        fclose(f);
        fprintf(stderr, "arena: cannot read %s\n", argv[1]);
        return 1;
    }
    fclose(f);
    if ((s = caveclod_hierarchy_open(file_bytes, (size_t)file_len, &h)) != CAVECLOD_STATUS_OK) {
        return fail("hierarchy", s, &arena);
    }
    caveclod_hierarchy_counts(&h, &hc);

    /* One camera of at most `budget` polygons, and index lists for that many. */
    caveclod_camera_config_polygon_budget(&h, (uint32_t)budget, &config);
    caveclod_camera_memory_size(&h, &config, &camera_bytes);
    if ((s = caveclod_arena_alloc(&arena, camera_bytes, CAVECLOD_MEMORY_ALIGN, &camera_memory)) !=
        CAVECLOD_STATUS_OK) {
        return fail("camera", s, &arena);
    }
    index_room = 3 * (size_t)(budget > hc.base_polygons ? budget : hc.base_polygons);
    if ((s = caveclod_arena_alloc(&arena, index_room * sizeof(uint32_t), 4, &indices)) !=
            CAVECLOD_STATUS_OK ||
        (s = caveclod_arena_alloc(&arena, (hc.surfaces + 1) * sizeof(uint32_t), 4, &offsets)) !=
            CAVECLOD_STATUS_OK) {
        return fail("indices", s, &arena);
    }
    if ((s = caveclod_camera_init(&h, &config, camera_memory, camera_bytes, &cam)) !=
        CAVECLOD_STATUS_OK) {
        return fail("camera", s, &arena);
    }

    for (i = 0; i < 3; ++i) {
        view.eye[i] = strtof(argv[2 + i], NULL);
        view.target[i] = strtof(argv[5 + i], NULL);
        view.up[i] = i == 1 ? 1.0f : 0.0f;
    }
    view.fov_y = 1.04719755119659774615f;
    view.aspect = 1280.0f / 720.0f;
    view.near = 0.1f;
    view.far = 1e5f;
    view.viewport_height = 720;
    caveclod_refine_params_default(&params);

    /* The frame loop: refine, emit, draw (here: count). */
    for (passes = 1; passes <= MAX_PASSES; ++passes) {
        if ((s = caveclod_camera_refine(&cam, &h, &view, &params, &stats)) != CAVECLOD_STATUS_OK) {
            return fail("refine", s, &arena);
        }
        if (stats.splits + stats.collapses == 0) {
            break;
        }
    }
    caveclod_camera_counts(&cam, &cc);
    s = caveclod_camera_emit_packed(&cam, &h, (uint32_t *)indices, index_room, (uint32_t *)offsets,
                                    hc.surfaces + 1, false, &total);
    if (s != CAVECLOD_STATUS_OK) {
        return fail("emit", s, &arena);
    }
    printf("{\"active_polygons\": %u, \"indices\": %lu, \"surfaces\": %u, \"budget\": %lu, "
           "\"arena_used\": %lu}\n",
           (unsigned)cc.active_polygons, (unsigned long)total, (unsigned)hc.surfaces, budget,
           (unsigned long)arena.used);
    return 0;
}
