/* refine.c: the C interface of caveclod from C99.
 *
 * usage: refine FILE.clod EX EY EZ TX TY TZ
 *
 * Reads the file into aligned memory, opens its hierarchy, refines one camera (eye E,
 * target T, +Y up, 1280 x 720, 60 degree vertical fov, near 0.1, far 1e5, tolerance 1 px,
 * culling on) until a pass changes nothing, emits its indices, and prints one JSON line
 * {"active_polygons": N, "indices": M, "surfaces": S}: what `caveclod refine FILE --eye
 * EX,EY,EZ --target TX,TY,TZ --json` prints for the same file and view. */

#include "caveclod.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* 64, not just CAVECLOD_BYTES_ALIGN: no record a refinement pass reads straddles two cache
 * lines. */
#define FILE_ALIGN 64
#define MAX_PASSES 1000

/* `size` bytes aligned to `align` (a power of two) from malloc; `*block` gets what to free. */
static void *aligned_malloc(size_t size, size_t align, void **block) {
    unsigned char *p = (unsigned char *)malloc(size + align);
    size_t misalignment;
    *block = p;
    if (p == NULL) {
        return NULL;
    }
    misalignment = (size_t)((uintptr_t)p % align);
    return p + (misalignment == 0 ? 0 : align - misalignment);
}

/* The whole file in aligned memory, or NULL. */
static unsigned char *read_file(const char *path, size_t *len, void **block) {
    FILE *f = fopen(path, "rb");
    long size;
    unsigned char *bytes = NULL;
    if (f == NULL) {
        return NULL;
    }
    if (fseek(f, 0, SEEK_END) == 0 && (size = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0) {
        bytes = (unsigned char *)aligned_malloc((size_t)size, FILE_ALIGN, block);
        if (bytes != NULL && fread(bytes, 1, (size_t)size, f) != (size_t)size) {
            free(*block);
            bytes = NULL;
        }
        *len = (size_t)size;
    }
    fclose(f);
    return bytes;
}

static int fail(const char *what, CaveclodStatus status) {
    fprintf(stderr, "refine: %s: %s\n", what, caveclod_status_message((int32_t)status));
    return 1;
}

int main(int argc, char **argv) {
    size_t len = 0, memory_bytes = 0, total = 0;
    void *file_block = NULL, *memory_block = NULL;
    unsigned char *bytes;
    void *memory;
    uint32_t *indices, *offsets;
    CaveclodHierarchy h;
    CaveclodHierarchyCounts hc;
    CaveclodCameraConfig config;
    CaveclodCamera cam;
    CaveclodCameraCounts cc;
    CaveclodRefineParams params;
    CaveclodRefineStats stats;
    CaveclodView view;
    CaveclodStatus s;
    int i, passes;

    if (argc != 8) {
        fprintf(stderr, "usage: refine FILE.clod EX EY EZ TX TY TZ\n");
        return 2;
    }
    if (caveclod_abi_version() >> 16 != CAVECLOD_ABI_VERSION >> 16) {
        fprintf(stderr, "refine: the library's ABI differs from the header's\n");
        return 1;
    }
    bytes = read_file(argv[1], &len, &file_block);
    if (bytes == NULL) {
        fprintf(stderr, "refine: cannot read %s\n", argv[1]);
        return 1;
    }
    if ((s = caveclod_hierarchy_open(bytes, len, &h)) != CAVECLOD_STATUS_OK) {
        return fail(argv[1], s);
    }
    caveclod_hierarchy_counts(&h, &hc);

    /* A camera that can reach full resolution, in memory of its own. */
    caveclod_camera_config_full(&h, &config);
    caveclod_camera_memory_size(&h, &config, &memory_bytes);
    memory = aligned_malloc(memory_bytes, CAVECLOD_MEMORY_ALIGN, &memory_block);
    if (memory == NULL) {
        fprintf(stderr, "refine: out of memory\n");
        return 1;
    }
    if ((s = caveclod_camera_init(&h, &config, memory, memory_bytes, &cam)) != CAVECLOD_STATUS_OK) {
        return fail("camera", s);
    }

    for (i = 0; i < 3; ++i) {
        view.eye[i] = strtof(argv[2 + i], NULL);
        view.target[i] = strtof(argv[5 + i], NULL);
        view.up[i] = i == 1 ? 1.0f : 0.0f;
    }
    view.fov_y = 1.04719755119659774615f; /* 60 degrees */
    view.aspect = 1280.0f / 720.0f;
    view.near = 0.1f;
    view.far = 1e5f;
    view.viewport_height = 720;
    caveclod_refine_params_default(&params); /* 1 px, frustum and back-face culling */

    for (passes = 1; passes <= MAX_PASSES; ++passes) {
        if ((s = caveclod_camera_refine(&cam, &h, &view, &params, &stats)) != CAVECLOD_STATUS_OK) {
            return fail("refine", s);
        }
        if (stats.splits + stats.collapses == 0) {
            break;
        }
    }

    caveclod_camera_counts(&cam, &cc);
    indices = (uint32_t *)malloc((size_t)cc.total_indices * sizeof(uint32_t) + 1);
    offsets = (uint32_t *)malloc((hc.surfaces + 1) * sizeof(uint32_t));
    if (indices == NULL || offsets == NULL) {
        fprintf(stderr, "refine: out of memory\n");
        return 1;
    }
    s = caveclod_camera_emit_packed(&cam, &h, indices, (size_t)cc.total_indices, offsets,
                                    hc.surfaces + 1, false, &total);
    if (s != CAVECLOD_STATUS_OK) {
        return fail("emit", s);
    }
    printf("{\"active_polygons\": %u, \"indices\": %lu, \"surfaces\": %u}\n",
           (unsigned)cc.active_polygons, (unsigned long)total, (unsigned)hc.surfaces);

    /* The camera and the hierarchy hold nothing: free their memory, then the file. */
    free(indices);
    free(offsets);
    free(memory_block);
    free(file_block);
    return 0;
}
