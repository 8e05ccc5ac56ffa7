/* stream.c: a paged .clod streamed through a page pool, the host doing the I/O.
 *
 * usage: stream FILE.clod [FRAMES [POOL_SLOTS]]
 *
 * Reads the file's root only, makes a pool of POOL_SLOTS slots (default: a quarter of the
 * streamed pages), then each frame wants a window of pages that slides over the file, asks
 * the pool which pages to load into which slots, reads them with fseek and fread, and hands
 * them back to the pool, which checks each one. A page that fails is reported once and
 * stays absent; the frames go on. Prints one JSON line with the totals. */

#include "caveclod.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define WINDOW 12

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
    CaveclodPageInfo info;
    CaveclodWanted wanted;
    CaveclodStatus s;
    FILE *f;
    void *root_bytes, *memory, *pool_bytes, *root_block = NULL, *memory_block, *pool_block;
    size_t root_len = 0, memory_len = 0;
    unsigned long frames = 200, installs = 0, evictions = 0, faults = 0, frame;
    uint32_t file, page, i, streamed;

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

    for (frame = 0; frame < frames; ++frame) {
        caveclod_pool_begin_frame(&pool);
        /* What the cameras want: a window sliding over the streamed pages. */
        for (i = 0; i < WINDOW && streamed > 0; ++i) {
            page = counts.root_pages + (uint32_t)((frame / 2 + i) % streamed);
            caveclod_paged_root_page(&root, page, &info);
            caveclod_pool_want(&pool, file, page, info.max_error, &wanted);
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
    }
    printf("{\"frames\": %lu, \"pages\": %u, \"slots\": %u, \"installs\": %lu, "
           "\"evictions\": %lu, \"faults\": %lu}\n",
           frames, counts.pages, config.slots, installs, evictions, faults);
    fclose(f);
    free(pool_block);
    free(memory_block);
    free(root_block);
    return 0;
}
