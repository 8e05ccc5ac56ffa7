// The C interface from C++17: bad input returns its documented status, two cameras refine
// over one hierarchy, every emitted index is checked against the vertex count, and the
// counts against the Rust API's (which `cargo xtask test` passes in, from `caveclod refine`).
//
// usage: capi_test FILE.clod  EX EY EZ TX TY TZ POLYGONS INDICES  EX EY EZ TX TY TZ POLYGONS INDICES
//                  OTHER.clod OCTREE.clod
// (OTHER.clod: any other hierarchy, for the cameras' wrong-hierarchy status; OCTREE.clod: an
// out-of-core bake, whose octree two cuts select)

#include "caveclod.h"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace {

int failures = 0;

void check(bool ok, const char *what, int line) {
    if (!ok) {
        std::fprintf(stderr, "FAIL line %d: %s\n", line, what);
        ++failures;
    }
}

#define CHECK(cond) check((cond), #cond, __LINE__)
#define CHECK_STATUS(call, expected)                                                           \
    do {                                                                                       \
        CaveclodStatus got_ = (call);                                                          \
        if (got_ != (expected)) {                                                              \
            std::fprintf(stderr, "FAIL line %d: %s returned %d (%s), expected %s\n", __LINE__, \
                         #call, static_cast<int>(got_),                                        \
                         caveclod_status_message(static_cast<int32_t>(got_)), #expected);      \
            ++failures;                                                                        \
        }                                                                                      \
    } while (0)

/// Bytes in memory aligned to 64, with room for a copy shifted by one byte.
struct AlignedBytes {
    std::vector<std::uint64_t> words;
    std::size_t len = 0;
    unsigned char *data() { return reinterpret_cast<unsigned char *>(words.data()); }
};

AlignedBytes read_file(const char *path) {
    std::ifstream f(path, std::ios::binary | std::ios::ate);
    AlignedBytes b;
    if (!f) {
        return b;
    }
    b.len = static_cast<std::size_t>(f.tellg());
    b.words.assign(b.len / 8 + 2, 0);
    f.seekg(0);
    f.read(reinterpret_cast<char *>(b.data()), static_cast<std::streamsize>(b.len));
    return b;
}

/// Memory aligned to 8 for a camera (plus a spare word, to misalign on purpose).
struct Memory {
    std::vector<std::uint64_t> words;
    explicit Memory(std::size_t bytes) : words(bytes / 8 + 2, 0) {}
    void *data() { return words.data(); }
};

CaveclodView view_of(const float eye[3], const float target[3]) {
    CaveclodView v{};
    for (int i = 0; i < 3; ++i) {
        v.eye[i] = eye[i];
        v.target[i] = target[i];
        v.up[i] = i == 1 ? 1.0f : 0.0f;
    }
    v.fov_y = 1.04719755119659774615f;
    v.aspect = 1280.0f / 720.0f;
    v.near = 0.1f;
    v.far = 1e5f;
    v.viewport_height = 720;
    return v;
}

/// Refines until a pass changes nothing; returns the passes.
int refine_to_rest(CaveclodCamera *cam, const CaveclodHierarchy *h, const CaveclodView &view) {
    CaveclodRefineParams params;
    CHECK_STATUS(caveclod_refine_params_default(&params), CAVECLOD_STATUS_OK);
    for (int pass = 1; pass <= 1000; ++pass) {
        CaveclodRefineStats stats{};
        CHECK_STATUS(caveclod_camera_refine(cam, h, &view, &params, &stats), CAVECLOD_STATUS_OK);
        if (stats.splits + stats.collapses == 0) {
            return pass;
        }
    }
    return 1000;
}

/// Emits per surface and packed; checks both agree, every index is below `bound`, and
/// returns the total.
std::size_t emit_and_check(CaveclodCamera *cam, const CaveclodHierarchy *h,
                           const CaveclodHierarchyCounts &hc, bool morphed, std::uint32_t bound) {
    CaveclodCameraCounts cc{};
    CHECK_STATUS(caveclod_camera_counts(cam, &cc), CAVECLOD_STATUS_OK);
    std::vector<std::uint32_t> packed(cc.total_indices), offsets(hc.surfaces + 1);
    std::size_t total = 0;
    CHECK_STATUS(caveclod_camera_emit_packed(cam, h, packed.data(), packed.size(), offsets.data(),
                                             offsets.size(), morphed, &total),
                 CAVECLOD_STATUS_OK);
    CHECK(total == cc.total_indices);
    CHECK(total % 3 == 0);
    CHECK(total == 3 * static_cast<std::size_t>(cc.active_polygons));
    for (std::uint32_t i : packed) {
        if (i >= bound) {
            std::fprintf(stderr, "FAIL: index %u out of range (bound %u)\n", i, bound);
            ++failures;
            break;
        }
    }
    std::vector<std::vector<std::uint32_t>> lists(hc.surfaces);
    std::vector<std::uint32_t *> pointers(hc.surfaces);
    std::vector<std::size_t> capacities(hc.surfaces);
    std::vector<std::uint32_t> written(hc.surfaces);
    for (std::uint32_t s = 0; s < hc.surfaces; ++s) {
        std::size_t n = 0;
        CHECK_STATUS(caveclod_camera_index_count(cam, s, &n), CAVECLOD_STATUS_OK);
        CHECK(n == offsets[s + 1] - offsets[s]);
        lists[s].assign(n + 1, 0);
        pointers[s] = lists[s].data();
        capacities[s] = lists[s].size();
    }
    std::size_t per_surface_total = 0;
    CHECK_STATUS(caveclod_camera_emit(cam, h, pointers.data(), capacities.data(), written.data(),
                                      hc.surfaces, morphed, &per_surface_total),
                 CAVECLOD_STATUS_OK);
    CHECK(per_surface_total == total);
    for (std::uint32_t s = 0; s < hc.surfaces; ++s) {
        CHECK(written[s] == offsets[s + 1] - offsets[s]);
        CHECK(std::memcmp(lists[s].data(), packed.data() + offsets[s],
                          written[s] * sizeof(std::uint32_t)) == 0);
    }
    return total;
}

/// Every bad input through the C interface returns its documented status.
void bad_inputs(AlignedBytes &file, const CaveclodHierarchy &h, const CaveclodHierarchyCounts &hc,
                const CaveclodHierarchy &other) {
    CaveclodHierarchy bad;
    // Null pointers.
    CHECK_STATUS(caveclod_hierarchy_open(nullptr, file.len, &bad), CAVECLOD_STATUS_NULL_POINTER);
    CHECK_STATUS(caveclod_hierarchy_open(file.data(), file.len, nullptr),
                 CAVECLOD_STATUS_NULL_POINTER);
    CHECK_STATUS(caveclod_hierarchy_counts(nullptr, nullptr), CAVECLOD_STATUS_NULL_POINTER);
    CHECK_STATUS(caveclod_hierarchy_counts(&h, nullptr), CAVECLOD_STATUS_NULL_POINTER);
    // Truncated files: shorter than the header, and shorter than the header says.
    CHECK_STATUS(caveclod_hierarchy_open(file.data(), 10, &bad), CAVECLOD_STATUS_TRUNCATED);
    CHECK_STATUS(caveclod_hierarchy_open(file.data(), file.len - 100, &bad),
                 CAVECLOD_STATUS_TRUNCATED);
    // Bytes after the end the header records (the buffer has zeroed room past the file).
    CHECK_STATUS(caveclod_hierarchy_open(file.data(), file.len + 8, &bad),
                 CAVECLOD_STATUS_TRAILING_BYTES);
    CHECK(std::strcmp(caveclod_status_message(CAVECLOD_STATUS_TRAILING_BYTES),
                      caveclod_status_message(CAVECLOD_STATUS_TRUNCATED)) != 0);
    // A failed open leaves a handle every call refuses.
    CaveclodHierarchyCounts unused{};
    CHECK_STATUS(caveclod_hierarchy_counts(&bad, &unused), CAVECLOD_STATUS_INVALID_HANDLE);
    CaveclodHierarchy zeroed{};
    CHECK_STATUS(caveclod_hierarchy_counts(&zeroed, &unused), CAVECLOD_STATUS_INVALID_HANDLE);
    CaveclodBounds no_bounds{};
    CHECK_STATUS(caveclod_hierarchy_bounds(&zeroed, &no_bounds), CAVECLOD_STATUS_INVALID_HANDLE);
    CHECK_STATUS(caveclod_hierarchy_bounds(&h, nullptr), CAVECLOD_STATUS_NULL_POINTER);
    // A misaligned pointer: the same bytes one byte in.
    {
        std::vector<std::uint64_t> shifted(file.words.size() + 1, 0);
        unsigned char *p = reinterpret_cast<unsigned char *>(shifted.data()) + 1;
        std::memcpy(p, file.data(), file.len);
        CHECK_STATUS(caveclod_hierarchy_open(p, file.len, &bad), CAVECLOD_STATUS_MISALIGNED);
    }
    // Not a .clod file, and a corrupt one (a byte flipped past the header).
    {
        AlignedBytes copy = file;
        copy.data()[0] ^= 0xff;
        CHECK_STATUS(caveclod_hierarchy_open(copy.data(), copy.len, &bad),
                     CAVECLOD_STATUS_NOT_A_CLOD_FILE);
        copy = file;
        copy.data()[copy.len / 2] ^= 0x5a;
        CHECK_STATUS(caveclod_hierarchy_open(copy.data(), copy.len, &bad), CAVECLOD_STATUS_CORRUPT);
    }

    // Camera memory: too little, misaligned, null; a configuration beyond the hierarchy.
    CaveclodCameraConfig config;
    CHECK_STATUS(caveclod_camera_config_full(&h, &config), CAVECLOD_STATUS_OK);
    std::size_t bytes = 0;
    CHECK_STATUS(caveclod_camera_memory_size(&h, &config, &bytes), CAVECLOD_STATUS_OK);
    Memory memory(bytes);
    CaveclodCamera cam;
    CHECK_STATUS(caveclod_camera_init(&h, &config, memory.data(), bytes - 1, &cam),
                 CAVECLOD_STATUS_MEMORY_TOO_SMALL);
    CaveclodCameraCounts cc{};
    CHECK_STATUS(caveclod_camera_counts(&cam, &cc), CAVECLOD_STATUS_INVALID_HANDLE);
    CHECK_STATUS(caveclod_camera_init(&h, &config,
                                      static_cast<unsigned char *>(memory.data()) + 4, bytes, &cam),
                 CAVECLOD_STATUS_MISALIGNED);
    CHECK_STATUS(caveclod_camera_init(&h, &config, nullptr, bytes, &cam),
                 CAVECLOD_STATUS_NULL_POINTER);
    CHECK_STATUS(caveclod_camera_init(&h, nullptr, memory.data(), bytes, &cam),
                 CAVECLOD_STATUS_NULL_POINTER);
    CHECK_STATUS(caveclod_camera_init(&zeroed, &config, memory.data(), bytes, &cam),
                 CAVECLOD_STATUS_INVALID_HANDLE);
    CaveclodCameraConfig too_many = config;
    too_many.max_pairs = hc.splits + 1;
    CHECK_STATUS(caveclod_camera_memory_size(&h, &too_many, &bytes), CAVECLOD_STATUS_INVALID_CONFIG);
    CHECK_STATUS(caveclod_camera_init(&h, &too_many, memory.data(), bytes, &cam),
                 CAVECLOD_STATUS_INVALID_CONFIG);

    // A working camera, then bad views, parameters and outputs.
    CHECK_STATUS(caveclod_camera_init(&h, &config, memory.data(), bytes, &cam), CAVECLOD_STATUS_OK);
    CHECK_STATUS(caveclod_camera_counts(&cam, nullptr), CAVECLOD_STATUS_NULL_POINTER);
    CHECK_STATUS(caveclod_camera_counts(nullptr, &cc), CAVECLOD_STATUS_NULL_POINTER);
    const float eye[3] = {0.0f, 0.0f, 3.0f}, target[3] = {0.0f, 0.0f, 0.0f};
    CaveclodView view = view_of(eye, target);
    CHECK_STATUS(caveclod_camera_refine(&cam, &h, nullptr, nullptr, nullptr),
                 CAVECLOD_STATUS_NULL_POINTER);
    CHECK_STATUS(caveclod_camera_refine(&cam, nullptr, &view, nullptr, nullptr),
                 CAVECLOD_STATUS_NULL_POINTER);
    CaveclodView degenerate = view_of(eye, eye);
    CHECK_STATUS(caveclod_camera_refine(&cam, &h, &degenerate, nullptr, nullptr),
                 CAVECLOD_STATUS_INVALID_ARGUMENT);
    CaveclodView no_height = view;
    no_height.viewport_height = 0;
    CHECK_STATUS(caveclod_camera_refine(&cam, &h, &no_height, nullptr, nullptr),
                 CAVECLOD_STATUS_INVALID_ARGUMENT);
    CaveclodRefineParams params;
    caveclod_refine_params_default(&params);
    // Parameters out of the core's ranges: a tolerance that is not a finite number above
    // 0, a negative time, a guard band of a right angle.
    for (float tolerance : {-1.0f, 0.0f}) {
        params.tolerance_px = tolerance;
        CHECK_STATUS(caveclod_camera_refine(&cam, &h, &view, &params, nullptr),
                     CAVECLOD_STATUS_INVALID_ARGUMENT);
    }
    caveclod_refine_params_default(&params);
    params.dt_s = -1.0f;
    CHECK_STATUS(caveclod_camera_refine(&cam, &h, &view, &params, nullptr),
                 CAVECLOD_STATUS_INVALID_ARGUMENT);
    caveclod_refine_params_default(&params);
    params.morph_guard_rad = 1.5708f;
    CHECK_STATUS(caveclod_camera_refine(&cam, &h, &view, &params, nullptr),
                 CAVECLOD_STATUS_INVALID_ARGUMENT);
    CHECK_STATUS(caveclod_camera_refine(&cam, &h, &view, nullptr, nullptr), CAVECLOD_STATUS_OK);
    std::size_t n = 0;
    CHECK_STATUS(caveclod_camera_index_count(&cam, hc.surfaces, &n), CAVECLOD_STATUS_INVALID_ARGUMENT);

    CHECK_STATUS(caveclod_camera_counts(&cam, &cc), CAVECLOD_STATUS_OK);
    CHECK(cc.total_indices > 0);
    std::vector<std::uint32_t> out(cc.total_indices), offsets(hc.surfaces + 1);
    CHECK_STATUS(caveclod_camera_emit_packed(&cam, &h, out.data(), out.size() - 1, offsets.data(),
                                             offsets.size(), false, nullptr),
                 CAVECLOD_STATUS_OUTPUT_TOO_SMALL);
    CHECK_STATUS(caveclod_camera_emit_packed(&cam, &h, out.data(), out.size(), offsets.data(),
                                             offsets.size() - 1, false, nullptr),
                 CAVECLOD_STATUS_OUTPUT_TOO_SMALL);
    CHECK_STATUS(caveclod_camera_emit_packed(&cam, &h, nullptr, out.size(), offsets.data(),
                                             offsets.size(), false, nullptr),
                 CAVECLOD_STATUS_NULL_POINTER);
    std::vector<std::uint32_t *> pointers(hc.surfaces, out.data());
    std::vector<std::size_t> capacities(hc.surfaces, 0);
    std::vector<std::uint32_t> written(hc.surfaces);
    // Every list empty: the first surface with polygons is too small.
    CHECK_STATUS(caveclod_camera_emit(&cam, &h, pointers.data(), capacities.data(), written.data(),
                                      hc.surfaces, false, nullptr),
                 CAVECLOD_STATUS_OUTPUT_TOO_SMALL);
    CHECK_STATUS(caveclod_camera_emit(&cam, &h, pointers.data(), capacities.data(), written.data(),
                                      hc.surfaces - 1, false, nullptr),
                 CAVECLOD_STATUS_OUTPUT_TOO_SMALL);
    CHECK_STATUS(caveclod_camera_emit(&cam, &h, nullptr, capacities.data(), written.data(),
                                      hc.surfaces, false, nullptr),
                 CAVECLOD_STATUS_NULL_POINTER);
    // A camera given another hierarchy, or an unopened one.
    CHECK_STATUS(caveclod_camera_refine(&cam, &other, &view, nullptr, nullptr),
                 CAVECLOD_STATUS_WRONG_HIERARCHY);
    CHECK_STATUS(caveclod_camera_reset(&cam, &other), CAVECLOD_STATUS_WRONG_HIERARCHY);
    CHECK_STATUS(caveclod_camera_emit_packed(&cam, &other, out.data(), out.size(), offsets.data(),
                                             offsets.size(), false, nullptr),
                 CAVECLOD_STATUS_WRONG_HIERARCHY);
    CHECK_STATUS(caveclod_camera_reset(&cam, &zeroed), CAVECLOD_STATUS_INVALID_HANDLE);
    CHECK_STATUS(caveclod_camera_reset(&cam, &h), CAVECLOD_STATUS_OK);

    // No octree in an in-core bake.
    CaveclodOctree octree;
    CHECK_STATUS(caveclod_octree_open(&h, &octree), CAVECLOD_STATUS_NO_OCTREE);
    std::size_t cut_bytes = 0;
    CHECK_STATUS(caveclod_octree_cut_memory_size(&octree, &cut_bytes), CAVECLOD_STATUS_INVALID_HANDLE);

    // An arena that fills reports it.
    unsigned char buffer[256];
    CaveclodArena arena;
    CHECK_STATUS(caveclod_arena_init(&arena, buffer, sizeof buffer), CAVECLOD_STATUS_OK);
    void *p = nullptr;
    CHECK_STATUS(caveclod_arena_alloc(&arena, 200, 8, &p), CAVECLOD_STATUS_OK);
    CHECK(p != nullptr);
    CHECK_STATUS(caveclod_arena_alloc(&arena, 100, 8, &p), CAVECLOD_STATUS_ARENA_FULL);
    CHECK(p == nullptr);
    CHECK_STATUS(caveclod_arena_alloc(&arena, 8, 3, &p), CAVECLOD_STATUS_INVALID_ARGUMENT);

    // Every status has a message, and so has a value that is none.
    for (int s = 0; s <= CAVECLOD_STATUS_INTERNAL + 1; ++s) {
        const char *m = caveclod_status_message(s);
        CHECK(m != nullptr && std::strlen(m) > 0);
    }
    CHECK(std::strcmp(caveclod_status_message(CAVECLOD_STATUS_OK), "success") == 0);
}

/// Two cuts of an out-of-core bake's octree: statuses, and every index below the octree's
/// vertex count.
void octree_cuts(const char *path) {
    AlignedBytes file = read_file(path);
    CaveclodHierarchy h;
    CHECK_STATUS(caveclod_hierarchy_open(file.data(), file.len, &h), CAVECLOD_STATUS_OK);
    CaveclodOctree o;
    CHECK_STATUS(caveclod_octree_open(&h, &o), CAVECLOD_STATUS_OK);
    CaveclodOctreeCounts oc{};
    CHECK_STATUS(caveclod_octree_counts(&o, &oc), CAVECLOD_STATUS_OK);
    CHECK(oc.nodes > 0 && oc.vertices > 0 && oc.vertex_buffer_bytes == 32ull * oc.vertices);
    const void *vertices = nullptr;
    std::size_t vertex_bytes = 0;
    CHECK_STATUS(caveclod_octree_vertices(&o, &vertices, &vertex_bytes), CAVECLOD_STATUS_OK);
    CHECK(vertices != nullptr && vertex_bytes == oc.vertex_buffer_bytes);
    std::size_t bytes = 0;
    CHECK_STATUS(caveclod_octree_cut_memory_size(&o, &bytes), CAVECLOD_STATUS_OK);
    Memory memory[2] = {Memory(bytes), Memory(bytes)};
    CaveclodOctreeCut cuts[2];
    CHECK_STATUS(caveclod_octree_cut_init(&o, memory[0].data(), bytes - 4, &cuts[0]),
                 CAVECLOD_STATUS_MEMORY_TOO_SMALL);
    CHECK_STATUS(caveclod_octree_cut_init(&o, static_cast<unsigned char *>(memory[0].data()) + 4,
                                          bytes, &cuts[0]),
                 CAVECLOD_STATUS_MISALIGNED);
    const float eyes[2][3] = {{0.0f, 0.3f, 2.5f}, {0.3f, 0.2f, 0.4f}};
    const float target[3] = {0.0f, 0.0f, 0.0f};
    for (int c = 0; c < 2; ++c) {
        CHECK_STATUS(caveclod_octree_cut_init(&o, memory[c].data(), bytes, &cuts[c]),
                     CAVECLOD_STATUS_OK);
        CaveclodView view = view_of(eyes[c], target);
        CaveclodSelectStats stats{};
        CHECK_STATUS(caveclod_octree_cut_select(&cuts[c], &o, &view, 1.0f, &stats),
                     CAVECLOD_STATUS_OK);
        CHECK(stats.selected > 0 && stats.triangles > 0);
        CHECK_STATUS(caveclod_octree_cut_select(&cuts[c], &o, &view, -1.0f, nullptr),
                     CAVECLOD_STATUS_INVALID_ARGUMENT);
        CHECK_STATUS(caveclod_octree_cut_select(&cuts[c], &o, &view, 0.0f, nullptr),
                     CAVECLOD_STATUS_INVALID_ARGUMENT);
        std::size_t total = 0, emitted = 0;
        CHECK_STATUS(caveclod_octree_cut_total_index_count(&cuts[c], &o, &total), CAVECLOD_STATUS_OK);
        CHECK(total == 3 * static_cast<std::size_t>(stats.triangles));
        std::vector<std::uint32_t> out(total), offsets(oc.surfaces + 1);
        CHECK_STATUS(caveclod_octree_cut_emit_packed(&cuts[c], &o, out.data(), total - 1,
                                                     offsets.data(), offsets.size(), nullptr),
                     CAVECLOD_STATUS_OUTPUT_TOO_SMALL);
        CHECK_STATUS(caveclod_octree_cut_emit_packed(&cuts[c], &o, out.data(), total,
                                                     offsets.data(), offsets.size(), &emitted),
                     CAVECLOD_STATUS_OK);
        CHECK(emitted == total && offsets[oc.surfaces] == total);
        for (std::uint32_t i : out) {
            if (i >= oc.vertices) {
                std::fprintf(stderr, "FAIL: octree index %u out of range (%u vertices)\n", i,
                             oc.vertices);
                ++failures;
                break;
            }
        }
        std::printf("octree cut %d: %u nodes, %u triangles\n", c, stats.selected, stats.triangles);
    }
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 20) {
        std::fprintf(stderr,
                     "usage: capi_test FILE.clod (EX EY EZ TX TY TZ POLYGONS INDICES) x 2 "
                     "OTHER.clod OCTREE.clod\n");
        return 2;
    }
    CHECK(caveclod_abi_version() >> 16 == CAVECLOD_ABI_VERSION >> 16);
    AlignedBytes file = read_file(argv[1]);
    CHECK(file.len > 0);
    CaveclodHierarchy h;
    CHECK_STATUS(caveclod_hierarchy_open(file.data(), file.len, &h), CAVECLOD_STATUS_OK);
    CaveclodHierarchyCounts hc{};
    CHECK_STATUS(caveclod_hierarchy_counts(&h, &hc), CAVECLOD_STATUS_OK);
    CHECK(hc.vertex_stride == 32 && hc.vertex_buffer_bytes == 32ull * hc.vertices);
    const void *vertices = nullptr;
    std::size_t vertex_bytes = 0;
    CHECK_STATUS(caveclod_hierarchy_vertices(&h, &vertices, &vertex_bytes), CAVECLOD_STATUS_OK);
    CHECK(vertices != nullptr && vertex_bytes == hc.vertex_buffer_bytes);
    // The model's bounds: a box with extent that holds every vertex of the buffer.
    CaveclodBounds bounds{};
    CHECK_STATUS(caveclod_hierarchy_bounds(&h, &bounds), CAVECLOD_STATUS_OK);
    bool inside = true;
    const unsigned char *vertex_bytes_at = static_cast<const unsigned char *>(vertices);
    for (std::uint32_t v = 0; v < hc.vertices; ++v) {
        float p[3];
        std::memcpy(p, vertex_bytes_at + 32ull * v + hc.position_offset, sizeof p);
        for (int k = 0; k < 3; ++k) {
            inside = inside && p[k] >= bounds.min[k] && p[k] <= bounds.max[k];
        }
    }
    CHECK(inside);
    CHECK(bounds.min[0] < bounds.max[0] && bounds.min[1] < bounds.max[1] &&
          bounds.min[2] < bounds.max[2]);

    AlignedBytes other_file = read_file(argv[18]);
    CaveclodHierarchy other;
    CHECK_STATUS(caveclod_hierarchy_open(other_file.data(), other_file.len, &other),
                 CAVECLOD_STATUS_OK);
    bad_inputs(file, h, hc, other);

    // Two full cameras over the one hierarchy, each with its own view, refined in turn.
    CaveclodCameraConfig config;
    CHECK_STATUS(caveclod_camera_config_full(&h, &config), CAVECLOD_STATUS_OK);
    std::size_t bytes = 0;
    CHECK_STATUS(caveclod_camera_memory_size(&h, &config, &bytes), CAVECLOD_STATUS_OK);
    Memory memory[2] = {Memory(bytes), Memory(bytes)};
    CaveclodCamera cams[2];
    CaveclodView views[2];
    unsigned long expected[2][2];
    for (int c = 0; c < 2; ++c) {
        char **a = argv + 2 + 8 * c;
        const float eye[3] = {std::strtof(a[0], nullptr), std::strtof(a[1], nullptr),
                              std::strtof(a[2], nullptr)};
        const float target[3] = {std::strtof(a[3], nullptr), std::strtof(a[4], nullptr),
                                 std::strtof(a[5], nullptr)};
        views[c] = view_of(eye, target);
        expected[c][0] = std::strtoul(a[6], nullptr, 10);
        expected[c][1] = std::strtoul(a[7], nullptr, 10);
        CHECK_STATUS(caveclod_camera_init(&h, &config, memory[c].data(), bytes, &cams[c]),
                     CAVECLOD_STATUS_OK);
    }
    CaveclodRefineParams params;
    caveclod_refine_params_default(&params);
    for (int round = 0; round < 1000; ++round) {
        std::uint32_t ops = 0;
        for (int c = 0; c < 2; ++c) {
            CaveclodRefineStats stats{};
            CHECK_STATUS(caveclod_camera_refine(&cams[c], &h, &views[c], &params, &stats),
                         CAVECLOD_STATUS_OK);
            ops += stats.splits + stats.collapses;
        }
        if (ops == 0) {
            break;
        }
    }
    for (int c = 0; c < 2; ++c) {
        CaveclodCameraCounts cc{};
        CHECK_STATUS(caveclod_camera_counts(&cams[c], &cc), CAVECLOD_STATUS_OK);
        std::size_t total = emit_and_check(&cams[c], &h, hc, false, hc.vertices);
        std::printf("camera %d: %u active polygons, %zu indices (Rust API: %lu, %lu)\n", c,
                    cc.active_polygons, total, expected[c][0], expected[c][1]);
        CHECK(cc.active_polygons == expected[c][0]);
        CHECK(total == expected[c][1]);
    }

    // A budgeted camera stays within its budget.
    const std::uint32_t budget = hc.base_polygons + 2000;
    CaveclodCameraConfig budgeted;
    CHECK_STATUS(caveclod_camera_config_polygon_budget(&h, budget, &budgeted), CAVECLOD_STATUS_OK);
    CHECK_STATUS(caveclod_camera_memory_size(&h, &budgeted, &bytes), CAVECLOD_STATUS_OK);
    Memory budget_memory(bytes);
    CaveclodCamera small;
    CHECK_STATUS(caveclod_camera_init(&h, &budgeted, budget_memory.data(), bytes, &small),
                 CAVECLOD_STATUS_OK);
    refine_to_rest(&small, &h, views[0]);
    CaveclodCameraCounts sc{};
    CHECK_STATUS(caveclod_camera_counts(&small, &sc), CAVECLOD_STATUS_OK);
    CHECK(sc.active_polygons <= budget);
    emit_and_check(&small, &h, hc, false, hc.vertices);

    // A camera with morph memory: morphed emission points at its morph slots.
    CaveclodCameraConfig morphing = config;
    morphing.max_morphs = 256;
    CHECK_STATUS(caveclod_camera_memory_size(&h, &morphing, &bytes), CAVECLOD_STATUS_OK);
    Memory morph_memory(bytes);
    CaveclodCamera morph_cam;
    CHECK_STATUS(caveclod_camera_init(&h, &morphing, morph_memory.data(), bytes, &morph_cam),
                 CAVECLOD_STATUS_OK);
    // A camera's first pass never morphs (nothing was drawn before it): draw the second
    // view first, then turn to the first, which morphs what it splits.
    CaveclodRefineStats ms{};
    CHECK_STATUS(caveclod_camera_refine(&morph_cam, &h, &views[1], &params, &ms), CAVECLOD_STATUS_OK);
    CHECK(ms.morphs_started == 0);
    CHECK_STATUS(caveclod_camera_refine(&morph_cam, &h, &views[0], &params, &ms), CAVECLOD_STATUS_OK);
    CHECK(ms.morphs_started > 0);
    const CaveclodMorphVertex *slots = nullptr;
    std::size_t slot_count = 0;
    CHECK_STATUS(caveclod_camera_morph_vertices(&morph_cam, &slots, &slot_count), CAVECLOD_STATUS_OK);
    CHECK(slot_count > 0 && slot_count <= 2 * morphing.max_morphs);
    for (std::size_t i = 0; i < slot_count; ++i) {
        const CaveclodMorphVertex &m = slots[i];
        // Idle; or a persistent `to` and `coarse`, and `from` either `coarse` or another
        // slot (the vertex split again while it morphed: it starts where that one is drawn).
        const bool idle = m.from == UINT32_MAX && m.to == UINT32_MAX;
        const bool from_ok = m.from == m.coarse
            || (m.from >= hc.vertices && m.from - hc.vertices < slot_count && m.from - hc.vertices != i);
        CHECK(idle || (m.to < hc.vertices && m.coarse < hc.vertices && from_ok));
    }
    emit_and_check(&morph_cam, &h, hc, true, hc.vertices + static_cast<std::uint32_t>(slot_count));

    octree_cuts(argv[19]);

    if (failures > 0) {
        std::fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    std::printf("capi_test: all checks passed\n");
    return 0;
}
