// gltf_io.cc — glTF 2.0 import/export and scene configs behind the C API of
// mr_scene.h. The only C++ file of lib/scene: tinygltf parses and writes the
// container; every accessor is read and bounds-checked here, because input
// files are untrusted. No C++ type or exception leaves this file.
#include "mr_scene.h"

#include <tiny_gltf.h>  // never TINYGLTF_IMPLEMENTATION: we link the shared lib

#include "draco_internal.h"
#include "ifc_internal.h"
#include "prepare_internal.h"
#include <meshoptimizer.h>

#include <stb_image.h>
#include <stb_image_write.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <condition_variable>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <deque>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

namespace {

// Internal error flow: thrown deep inside validation, caught at the C border.
struct Fail {
    mr_err_code code;
    std::string msg;
};

[[noreturn]] void fail(mr_err_code code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void fail(mr_err_code code, const char *fmt, ...) {
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    throw Fail{code, buf};
}

// tinygltf messages are multi-line; ours must be one line.
std::string one_line(const std::string &s) {
    std::string out;
    out.reserve(s.size());
    for (char c : s) {
        if (c == '\n' || c == '\r') {
            if (!out.empty() && out.back() != ' ' && out.back() != ';') out += "; ";
        } else {
            out += c;
        }
    }
    while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
    if (out.size() > 1000) out = out.substr(0, 1000) + "...";  // e.g. a data: URI quoted back at us
    return out;
}

// Owns a scene until it is handed to the caller.
struct SceneGuard {
    mr_scene *s;
    explicit SceneGuard(mr_scene *p) : s(p) {}
    ~SceneGuard() { mr_scene_destroy(&s); }
    mr_scene *release() {
        mr_scene *p = s;
        s = nullptr;
        return p;
    }
    SceneGuard(const SceneGuard &) = delete;
    SceneGuard &operator=(const SceneGuard &) = delete;
};

// Owns the malloc'd arrays of a mesh until mr_scene_add_mesh takes them.
struct MeshGuard {
    mr_mesh m;
    mr_scene *blocks = nullptr;  // arrays inside its blocks are the scene's (mr_scene_adopt_block)
    MeshGuard() { std::memset(&m, 0, sizeof m); }
    ~MeshGuard() {
        for (void *p : {(void *)m.positions, (void *)m.normals, (void *)m.uvs, (void *)m.indices})
            mr_scene_array_free(blocks, p);
    }
    MeshGuard(const MeshGuard &) = delete;
    MeshGuard &operator=(const MeshGuard &) = delete;
};

// A big array's pages are first touched while it is filled, one fault
// (and one zeroed 4 KiB page) at a time: for a large mesh that is a third
// of its load (measured on the 2M-triangle unique factory packed with
// gltfpack -c). Where the kernel gives transparent huge pages on request
// (the Debian default, "madvise"), such arrays ask for them: 512 times fewer
// faults. Still plain malloc memory, freed with free().
void want_huge_pages(void *p, size_t bytes) {
    const size_t huge = (size_t)2 << 20;
    if (bytes < 2 * huge) return;
    uintptr_t a = ((uintptr_t)p + huge - 1) & ~(uintptr_t)(huge - 1), e = ((uintptr_t)p + bytes) & ~(uintptr_t)(huge - 1);
    if (e > a) (void)madvise(reinterpret_cast<void *>(a), e - a, MADV_HUGEPAGE);  // a hint: failure changes nothing
}

template <typename T>
T *xmalloc(size_t n) {
    if (n == 0) n = 1;
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_alloc();
    const size_t bytes = n * sizeof(T), huge = (size_t)2 << 20;
    void *v = nullptr;
    if (bytes >= 2 * huge && bytes <= SIZE_MAX - huge) {
        // Whole huge pages: malloc's block starts 16 bytes into its
        // mapping, so its first and last 2 MiB took 4 KiB faults, which
        // cost 3.5 times as much per byte as huge ones (22 MB first
        // touched: 15 ms in 4 KiB pages, 4.3 ms in huge ones). Measured on
        // the 2M unique factory (forked loads, medians of 21): gltfpack
        // 29.6 -> 22.9 ms, gltfpack -c 35.6 -> 31.2 ms.
        const size_t whole = (bytes + huge - 1) & ~(huge - 1);
        if (posix_memalign(&v, huge, whole) != 0) v = nullptr;
        if (v) want_huge_pages(v, whole);
    } else {
        v = std::malloc(bytes);
        if (v) want_huge_pages(v, bytes);
    }
    if (!v) throw std::bad_alloc();
    return static_cast<T *>(v);
}

// ------------------------------------------------------------- images

const int k_max_image_side = 16384;

// Decodes PNG/JPEG/... to RGBA8 with stb_image. Bytes are trusted to be in
// bounds here (the caller checked them).
// glTF extras <-> cJSON, for the element identity they carry (element.c).
cJSON *value_to_json(const tinygltf::Value &v, int depth = 0) {
    if (depth > 32) return cJSON_CreateNull();
    if (v.IsBool()) return cJSON_CreateBool(v.Get<bool>());
    if (v.IsNumber()) return cJSON_CreateNumber(v.GetNumberAsDouble());
    if (v.IsString()) return cJSON_CreateString(v.Get<std::string>().c_str());
    if (v.IsArray()) {
        cJSON *a = cJSON_CreateArray();
        for (size_t i = 0; a && i < v.ArrayLen(); i++) cJSON_AddItemToArray(a, value_to_json(v.Get((int)i), depth + 1));
        return a;
    }
    if (v.IsObject()) {
        cJSON *o = cJSON_CreateObject();
        for (const std::string &k : v.Keys())
            if (o) cJSON_AddItemToObject(o, k.c_str(), value_to_json(v.Get(k), depth + 1));
        return o;
    }
    return cJSON_CreateNull();
}

tinygltf::Value json_to_value(const cJSON *j) {
    if (cJSON_IsBool(j)) return tinygltf::Value(cJSON_IsTrue(j) ? true : false);
    if (cJSON_IsNumber(j)) return tinygltf::Value(j->valuedouble);
    if (cJSON_IsString(j)) return tinygltf::Value(std::string(j->valuestring));
    if (cJSON_IsArray(j)) {
        tinygltf::Value::Array a;
        const cJSON *c;
        cJSON_ArrayForEach(c, j) a.push_back(json_to_value(c));
        return tinygltf::Value(a);
    }
    if (cJSON_IsObject(j)) {
        tinygltf::Value::Object o;
        const cJSON *c;
        cJSON_ArrayForEach(c, j) if (c->string) o[c->string] = json_to_value(c);
        return tinygltf::Value(o);
    }
    return tinygltf::Value();
}

bool decode_image(const unsigned char *bytes, size_t size, tinygltf::Image *img, std::string *why) {
    if (!bytes || size == 0 || size > (size_t)INT_MAX) {
        *why = "empty or oversized image data";
        return false;
    }
    int w = 0, h = 0, n = 0;
    if (!stbi_info_from_memory(bytes, (int)size, &w, &h, &n)) {
        *why = std::string("cannot decode image (") + stbi_failure_reason() + ")";
        return false;
    }
    if (w <= 0 || h <= 0 || w > k_max_image_side || h > k_max_image_side) {
        *why = "image size " + std::to_string(w) + "x" + std::to_string(h) + " is out of range";
        return false;
    }
    unsigned char *px = stbi_load_from_memory(bytes, (int)size, &w, &h, &n, 4);
    if (!px) {
        *why = std::string("cannot decode image (") + stbi_failure_reason() + ")";
        return false;
    }
    img->image.assign(px, px + (size_t)w * (size_t)h * 4);
    stbi_image_free(px);
    img->width = w;
    img->height = h;
    img->component = 4;
    img->bits = 8;
    img->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
    return true;
}

// Image callback for tinygltf. For images in a bufferView tinygltf hands us a
// pointer it has not bounds-checked against the buffer, so those are not
// touched here but decoded later, after our own checks. Decode failures are
// warnings: the model still loads, without that texture.
bool image_loader(tinygltf::Image *image, const int idx, std::string *, std::string *warn, int, int,
                  const unsigned char *bytes, int size, void *) {
    if (image->bufferView >= 0) return true;
    std::string why;
    if (size <= 0 || !decode_image(bytes, (size_t)size, image, &why)) {
        image->image.clear();
        if (warn) *warn += "image " + std::to_string(idx) + ": " + (why.empty() ? "no data" : why) + "\n";
    }
    return true;
}

// With no base folder, external files are refused.
bool fs_no_exists(const std::string &, void *) { return false; }
std::string fs_no_expand(const std::string &p, void *) { return p; }
bool fs_no_read(std::vector<unsigned char> *, std::string *err, const std::string &p, void *) {
    if (err) *err = "external file '" + p + "' is not allowed here";
    return false;
}
bool fs_no_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *) {
    if (err) *err = "writing is not allowed";
    return false;
}

// ------------------------------------------------------------ buffers

// A read-only file mapping (the file itself, or an external .bin): big
// files are mapped, never copied, so a load's peak memory is about what it
// decodes, not file + copy + decoded.
struct Mapping {
    void *addr = nullptr;
    size_t len = 0;
    Mapping() = default;
    Mapping(const Mapping &) = delete;
    Mapping &operator=(const Mapping &) = delete;
    ~Mapping() {
        if (addr) munmap(addr, len);
    }
    // Gives back the pages read so far (they stay in the page cache and come
    // back if read again): resident file pages count in our RSS.
    void drop() const {
        if (addr) madvise(addr, len, MADV_DONTNEED);
    }
};

// Largest file we map: GLB lengths are 32-bit, and tinygltf takes the JSON's
// length as unsigned int.
const size_t k_max_file = (size_t)UINT32_MAX;

void map_file(const std::string &path, Mapping *mp) {
    int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) fail(MR_ERR_IO, "cannot open %s: %s", path.c_str(), std::strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        fail(MR_ERR_IO, "%s is not a regular file", path.c_str());
    }
    if ((unsigned long long)st.st_size > (unsigned long long)k_max_file) {
        close(fd);
        fail(MR_ERR_UNSUPPORTED, "%s is %.2f GB, over glTF's 4 GiB limit (GLB lengths are 32-bit)", path.c_str(),
             (double)st.st_size / 1e9);
    }
    size_t n = (size_t)st.st_size;
    if (n == 0) {
        close(fd);
        fail(MR_ERR_PARSE, "%s is empty", path.c_str());
    }
    void *p = mmap(nullptr, n, PROT_READ, MAP_PRIVATE, fd, 0);
    close(fd);
    if (p == MAP_FAILED) fail(MR_ERR_NOMEM, "cannot map %s (%zu bytes): %s", path.c_str(), n, std::strerror(errno));
    madvise(p, n, MADV_SEQUENTIAL);  // meshes are read in file order, mostly
    mp->addr = p;
    mp->len = n;
}

// One glTF buffer as the loader sees it: bytes we own or map, never a
// tinygltf copy (data: URIs excepted: tinygltf decodes those).
struct BufRef {
    const unsigned char *p = nullptr;
    size_t n = 0;
    bool fallback = false;  // EXT_meshopt_compression's fallback: no data
    bool data_uri = false;  // filled from tinygltf's decoded vector
};

struct Source {
    std::vector<BufRef> bufs;
    std::vector<std::unique_ptr<Mapping>> maps;  // external .bin files
    std::map<std::pair<int, int>, int> moved_indices;  // (mesh, primitive) -> index accessor without bufferView
    const Mapping *container = nullptr;          // the mapped .glb/.gltf, if it is one
    size_t input_bytes = 0;                      // file + external buffers: the bound on zero-filled accessors
    size_t since_drop = 0;
    size_t total_read = 0;  // bytes of accessors and streams read: the load's progress
    void consumed(size_t n) {
        total_read += n;
        since_drop += n;
        if (since_drop < ((size_t)64 << 20)) return;
        since_drop = 0;
        if (container) container->drop();
        for (const std::unique_ptr<Mapping> &m : maps) m->drop();
    }
};

uint32_t rd32(const unsigned char *p) {
    uint32_t v;
    std::memcpy(&v, p, 4);
    return v;  // GLB is little-endian, like every machine we build for
}

struct Glb {
    const char *json = nullptr;
    size_t json_len = 0;
    const unsigned char *bin = nullptr;
    size_t bin_len = 0;
    bool has_bin = false;
};

// The GLB container, checked here rather than by tinygltf, which would copy
// the BIN chunk into a vector.
Glb glb_split(const unsigned char *b, size_t size) {
    Glb g;
    if (size < 20) fail(MR_ERR_PARSE, "invalid GLB: %zu bytes is too short for a GLB header", size);
    uint32_t version = rd32(b + 4), length = rd32(b + 8);
    if (version != 2) fail(MR_ERR_PARSE, "invalid GLB: version %u (only 2 is supported)", version);
    if (length > size)
        fail(MR_ERR_PARSE, "invalid GLB: truncated (the header says %u bytes, there are %zu)", length, size);
    if (length < 20) fail(MR_ERR_PARSE, "invalid GLB: the header's length %u is too short", length);
    size = length;
    uint32_t jl = rd32(b + 12), jt = rd32(b + 16);
    if (jt != 0x4E4F534Au) fail(MR_ERR_PARSE, "invalid GLB: the first chunk is not JSON");
    if (jl > size - 20)
        fail(MR_ERR_PARSE, "invalid GLB: the JSON chunk (%u bytes) runs past the end of the file (%zu bytes)", jl, size);
    g.json = reinterpret_cast<const char *>(b + 20);
    g.json_len = jl;
    size_t off = 20 + (size_t)jl;
    while (size - off >= 8) {
        uint32_t cl = rd32(b + off), ct = rd32(b + off + 4);
        if (cl > size - off - 8)
            fail(MR_ERR_PARSE, "invalid GLB: the chunk at byte %zu (%u bytes) runs past the end of the file (%zu bytes)",
                 off, cl, size);
        if (ct == 0x004E4942u && !g.has_bin) {
            g.bin = b + off + 8;
            g.bin_len = cl;
            g.has_bin = true;
        }
        off += 8 + (size_t)cl;
    }
    return g;
}

struct JsonGuard {
    cJSON *j;
    ~JsonGuard() { cJSON_Delete(j); }
};

// Required extensions: those we read, and those that change nothing we read.
bool extension_ok(const std::string &e) {
    return e == "KHR_materials_unlit" || e == "KHR_materials_emissive_strength" || e == "KHR_mesh_quantization" ||
           e == "EXT_meshopt_compression" || e == "KHR_draco_mesh_compression" || e == "KHR_texture_transform";
}

std::string url_decode(const std::string &s) {
    std::string out;
    for (size_t i = 0; i < s.size(); i++) {
        if (s[i] == '%' && i + 2 < s.size() && std::isxdigit((unsigned char)s[i + 1]) &&
            std::isxdigit((unsigned char)s[i + 2])) {
            out += (char)std::stoi(s.substr(i + 1, 2), nullptr, 16);
            i += 2;
        } else {
            out += s[i];
        }
    }
    return out;
}

// Top-level members of a JSON object: key -> [begin, end) of its value.
// The whole text is only scanned (strings and nesting), never built as a
// tree: a CAD file's JSON can be large, and take_buffers needs only a few
// small members of it. False if the text is not an object; tinygltf then
// says what is wrong.
struct Span {
    size_t b, e;
};

bool skip_string(const char *s, size_t n, size_t *i) {
    for (size_t k = *i + 1; k < n; k++) {
        if (s[k] == '\\') k++;
        else if (s[k] == '"') {
            *i = k + 1;
            return true;
        }
    }
    return false;
}

bool skip_value(const char *s, size_t n, size_t *i) {
    size_t k = *i;
    if (k >= n) return false;
    if (s[k] == '"') return skip_string(s, n, i);
    if (s[k] == '{' || s[k] == '[') {
        int depth = 0;
        while (k < n) {
            char c = s[k];
            if (c == '"') {
                if (!skip_string(s, n, &k)) return false;
                continue;
            }
            if (c == '{' || c == '[') depth++;
            else if (c == '}' || c == ']') {
                if (--depth == 0) {
                    *i = k + 1;
                    return true;
                }
            }
            k++;
        }
        return false;
    }
    while (k < n && !std::strchr(",}] \t\r\n", s[k])) k++;
    if (k == *i) return false;
    *i = k;
    return true;
}

bool top_level(const char *s, size_t n, std::map<std::string, Span> *out) {
    auto ws = [&](size_t &k) {
        while (k < n && (s[k] == ' ' || s[k] == '\t' || s[k] == '\r' || s[k] == '\n')) k++;
    };
    size_t k = 0;
    ws(k);
    if (k >= n || s[k] != '{') return false;
    k++;
    ws(k);
    if (k < n && s[k] == '}') return true;
    while (k < n) {
        ws(k);
        if (k >= n || s[k] != '"') return false;
        size_t ks = k;
        if (!skip_string(s, n, &k)) return false;
        std::string key(s + ks + 1, k - ks - 2);
        ws(k);
        if (k >= n || s[k] != ':') return false;
        k++;
        ws(k);
        size_t vb = k;
        if (!skip_value(s, n, &k)) return false;
        out->emplace(key, Span{vb, k});
        ws(k);
        if (k < n && s[k] == ',') {
            k++;
            continue;
        }
        return k < n && s[k] == '}';
    }
    return false;
}

// Takes the buffers out of tinygltf's hands: the GLB's BIN chunk and
// external .bin files are mapped into src->bufs and replaced in the JSON by
// a 1-byte data URI, so tinygltf copies nothing big (its API has no way to
// hand it a buffer it does not own). Meshopt fallback buffers (no data at
// all) are marked, which also ends tinygltf's misleading "Invalid
// `byteLength'" on gltfpack -c output. data: URIs stay with tinygltf. A
// required extension we do not read is refused here, by name, before any
// buffer error can hide it. Only the members changed are re-printed and
// spliced into the text. Returns the JSON to parse.
//
// only_tinygltf: tinygltf keeps the buffers; only what it cannot read at
// all changes (meshopt fallback buffers, draco's indices without a
// bufferView) and nothing is refused (mr_gltf_parse_only). *changed: the
// text was changed.
std::string take_buffers(const char *json, size_t len, const Glb *glb, const char *base_dir, Source *src,
                         bool only_tinygltf = false, bool *changed_out = nullptr) {
    if (changed_out) *changed_out = false;
    std::map<std::string, Span> top;
    if (!top_level(json, len, &top)) return std::string(json, len);  // tinygltf says what is wrong
    auto member = [&](const char *key) -> cJSON * {
        auto it = top.find(key);
        return it == top.end() ? nullptr : cJSON_ParseWithLength(json + it->second.b, it->second.e - it->second.b);
    };
    std::map<size_t, std::pair<Span, std::string>> splice;  // by begin: the new text of a member's value
    auto replace = [&](const char *key, const cJSON *v) {
        char *t = cJSON_PrintUnformatted(v);
        if (!t) throw std::bad_alloc();
        const Span sp = top[key];
        splice[sp.b] = std::make_pair(sp, std::string(t));
        cJSON_free(t);
    };
    if (!only_tinygltf) {
        JsonGuard req{member("extensionsRequired")};
        const cJSON *r;
        cJSON_ArrayForEach(r, req.j) {
            if (cJSON_IsString(r) && !extension_ok(r->valuestring))
                fail(MR_ERR_UNSUPPORTED, "requires glTF extension %s (not supported)", r->valuestring);
        }
    }
    // tinygltf refuses index accessors without a bufferView, which draco
    // primitives have (their indices are in the draco data; the
    // specification allows them anywhere): such indices are kept aside.
    bool draco = false;
    {
        JsonGuard used{member("extensionsUsed")};
        const cJSON *u;
        cJSON_ArrayForEach(u, used.j) draco = draco || (cJSON_IsString(u) && !std::strcmp(u->valuestring, "KHR_draco_mesh_compression"));
    }
    if (draco) {
        JsonGuard accs{member("accessors")}, meshes{member("meshes")};
        bool changed = false;
        const cJSON *mesh;
        int mi = 0;
        cJSON_ArrayForEach(mesh, meshes.j) {
            cJSON *prim;
            int pi = 0;
            cJSON_ArrayForEach(prim, cJSON_GetObjectItemCaseSensitive(mesh, "primitives")) {
                const cJSON *ix = cJSON_GetObjectItemCaseSensitive(prim, "indices");
                if (cJSON_IsNumber(ix) && ix->valuedouble >= 0 && ix->valuedouble < (double)cJSON_GetArraySize(accs.j)) {
                    const cJSON *a = cJSON_GetArrayItem(accs.j, (int)ix->valuedouble);
                    if (cJSON_IsObject(a) && !cJSON_GetObjectItemCaseSensitive(a, "bufferView")) {
                        src->moved_indices[std::make_pair(mi, pi)] = (int)ix->valuedouble;
                        cJSON_DeleteItemFromObjectCaseSensitive(prim, "indices");
                        changed = true;
                    }
                }
                pi++;
            }
            mi++;
        }
        if (changed) replace("meshes", meshes.j);
    }
    JsonGuard bufs{member("buffers")};
    bool changed = false;
    int i = 0;
    cJSON *b;
    cJSON_ArrayForEach(b, bufs.j) {
        if (!cJSON_IsObject(b)) fail(MR_ERR_PARSE, "buffer %d is not an object", i);
        const cJSON *bl = cJSON_GetObjectItemCaseSensitive(b, "byteLength");
        if (!cJSON_IsNumber(bl) || !(bl->valuedouble >= 0) || bl->valuedouble > 9.0e15 ||
            std::floor(bl->valuedouble) != bl->valuedouble)
            fail(MR_ERR_PARSE, "buffer %d: byteLength must be a non-negative integer", i);
        BufRef ref;
        ref.n = (size_t)bl->valuedouble;
        const cJSON *uri = cJSON_GetObjectItemCaseSensitive(b, "uri");
        const char *u = cJSON_IsString(uri) ? uri->valuestring : "";
        const cJSON *mx = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(b, "extensions"),
                                                           "EXT_meshopt_compression");
        if (only_tinygltf) {
            // tinygltf takes a GLB's buffer without a uri for its BIN chunk,
            // and then refuses it as longer than the chunk: gltfpack -c's
            // fallback buffer gets one byte of its own instead.
            if (!u[0] && cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(mx, "fallback"))) {
                cJSON_DeleteItemFromObjectCaseSensitive(b, "byteLength");
                cJSON_AddStringToObject(b, "uri", "data:application/octet-stream;base64,AA==");
                cJSON_AddNumberToObject(b, "byteLength", 1);
                changed = true;
            }
            i++;
            continue;
        }
        if (std::strncmp(u, "data:", 5) == 0) {
            ref.data_uri = true;
            src->bufs.push_back(ref);
            i++;
            continue;
        }
        if (u[0]) {
            std::string name = url_decode(u);
            if (!base_dir) fail(MR_ERR_PARSE, "buffer %d: external file '%s' is not allowed here", i, name.c_str());
            char full[4096];
            mr_path_join(base_dir, name.c_str(), full, sizeof full);
            std::unique_ptr<Mapping> mp(new Mapping);
            map_file(full, mp.get());
            if (mp->len < ref.n)
                fail(MR_ERR_PARSE, "buffer %d: '%s' has %zu bytes, fewer than its byteLength %zu", i, name.c_str(),
                     mp->len, ref.n);
            ref.p = static_cast<const unsigned char *>(mp->addr);
            src->input_bytes += mp->len;
            src->maps.push_back(std::move(mp));
        } else if (cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(mx, "fallback"))) {
            ref.fallback = true;
        } else if (glb && i == 0 && glb->has_bin) {
            if (ref.n > glb->bin_len)
                fail(MR_ERR_PARSE, "buffer 0: byteLength %zu runs past the end of the GLB's BIN chunk (%zu bytes)", ref.n,
                     glb->bin_len);
            ref.p = glb->bin;
        } else {
            fail(MR_ERR_PARSE, "buffer %d has no data (no uri%s)", i,
                 glb ? (glb->has_bin ? ", and only buffer 0 is the GLB's BIN chunk" : ", and the GLB has no BIN chunk")
                     : "");
        }
        cJSON_DeleteItemFromObjectCaseSensitive(b, "uri");
        cJSON_DeleteItemFromObjectCaseSensitive(b, "byteLength");
        cJSON_AddStringToObject(b, "uri", "data:application/octet-stream;base64,AA==");
        cJSON_AddNumberToObject(b, "byteLength", 1);
        changed = true;
        src->bufs.push_back(ref);
        i++;
    }
    if (changed) replace("buffers", bufs.j);
    if (splice.empty()) return std::string(json, len);
    if (changed_out) *changed_out = true;
    std::string out;
    out.reserve(len + 256);
    size_t at = 0;
    for (const auto &kv : splice) {
        out.append(json + at, kv.second.first.b - at);
        out += kv.second.second;
        at = kv.second.first.e;
    }
    out.append(json + at, len - at);
    return out;
}

// ------------------------------------------------------------ accessors

int component_size(int type) {
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
    }
}

int type_components(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    default: return 0;
    }
}

// One component as a number: normalised integers as the specification
// maps them (unsigned c/max, signed max(c/max, -1)), others as they are.
double comp_value(const unsigned char *p, int comp, bool norm) {
    switch (comp) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        double v = (double)(int8_t)p[0];
        return norm ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return norm ? p[0] / 255.0 : (double)p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p, 2);
        return norm ? std::max(v / 32767.0, -1.0) : (double)v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p, 2);
        return norm ? v / 65535.0 : (double)v;
    }
    case TINYGLTF_COMPONENT_TYPE_INT: {
        int32_t v;
        std::memcpy(&v, p, 4);
        return (double)v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return (double)v;
    }
    default: {
        float f;
        std::memcpy(&f, p, 4);
        return (double)f;
    }
    }
}

// A validated window onto accessor data: element i starts at base +
// i*stride and all count elements lie inside their buffer. base is NULL for
// an accessor without a bufferView (zeros, then its sparse values).
struct View {
    const unsigned char *base;
    size_t stride, count;
    int comp, ncomp;
    bool normalized;
    int index;
    bool ready;  // its final array is already converted (Loader::ready): base is not to be read
};

// What a primitive reads an accessor as (Loader::preconvert).
enum Role { k_role_none = -1, k_role_position, k_role_normal, k_role_uv, k_role_index, k_role_mixed };

// A second core for a load. Tasks run on one helper thread, started with
// the first task, and on the loading thread whenever it waits (help): so
// both cores work while there is work, and where no second thread can be
// had every task still runs, on the loading thread, when it is waited for.
// A task never throws and touches only what it was given; whoever submits
// one waits for it before what it touches goes (shutdown drops the tasks
// not started yet and waits for the running one).
struct Pool {
    struct Task {
        std::function<void()> fn;
        bool done = false;  // under mu
    };
    std::mutex mu;
    // One signal for both events (a task queued, a task done): a thread
    // waiting in help() must wake for either. With a signal for each, it
    // slept through the halves queued after it began to wait, and the other
    // core ran them alone (measured on the 2M unique factory, gltfpack -c:
    // the loading thread idle for the last 11 of 30 ms).
    std::condition_variable changed;
    std::deque<Task *> queue;
    std::thread helper;
    bool stop = false, tried = false;

    Pool() = default;
    Pool(const Pool &) = delete;
    Pool &operator=(const Pool &) = delete;
    ~Pool() { shutdown(); }

    void shutdown() {
        {
            std::lock_guard<std::mutex> l(mu);
            stop = true;
            queue.clear();
        }
        changed.notify_all();
        if (helper.joinable()) helper.join();
    }

    // The helper thread, once (also by the first submit): a big file's
    // load starts it before the JSON is parsed, so that it is running when
    // the first task comes (measured: a thread started at the first task
    // took 0.8 to 2 ms to run it, on a 25 ms load).
    void start() {
        if (tried) return;
        tried = true;
        if (std::thread::hardware_concurrency() < 2) return;
        try {
            helper = std::thread([this] { loop(); });
        } catch (const std::system_error &) {
            // no helper: tasks run when waited for
        }
    }

    // urgent: ahead of what waits (work that frees memory or that the
    // loading thread is about to wait for).
    void submit(Task *t, bool urgent = false) {
        start();
        {
            std::lock_guard<std::mutex> l(mu);
            t->done = false;
            if (urgent) queue.push_front(t);
            else queue.push_back(t);
        }
        changed.notify_all();
    }

    // Pops and runs one task; called with l locked, returns with it locked.
    void run_one(std::unique_lock<std::mutex> &l) {
        Task *t = queue.front();
        queue.pop_front();
        l.unlock();
        t->fn();
        l.lock();
        t->done = true;
        changed.notify_all();
    }

    void loop() {
        std::unique_lock<std::mutex> l(mu);
        for (;;) {
            changed.wait(l, [&] { return stop || !queue.empty(); });
            if (stop) return;
            run_one(l);
        }
    }

    // Runs queued tasks here until pred() holds (checked under the lock).
    template <typename P>
    void help(P pred) {
        std::unique_lock<std::mutex> l(mu);
        while (!pred()) {
            if (!queue.empty()) run_one(l);
            else changed.wait(l);
        }
    }
    void wait(Task &t) {
        help([&] { return t.done; });
    }
    bool is_done(Task &t) {
        std::lock_guard<std::mutex> l(mu);
        return t.done;
    }
};

// -------------------------------------------------------------- loader

struct Loader {
    const tinygltf::Model &m;
    mr_scene *s;
    Source &src;
    bool quantized = false;  // KHR_mesh_quantization used: integer attributes allowed
    // Decoded EXT_meshopt_compression views, each freed once the accessors
    // of primitives that read it are read (view_uses), so a compressed file
    // never holds all its decoded bytes at once; a view read again after
    // that is decoded again.
    std::map<int, std::unique_ptr<unsigned char[]>> meshopt;
    std::vector<int> view_uses;
    // Compressed files must load at least as fast as plain ones, and a
    // decoded view's fresh pages cost as much as decoding
    // it. So a meshopt view whose every reader is a primitive attribute or
    // index list read once (view_pre) is decoded into one scratch buffer,
    // reused by all such views and sized for the largest (scratch_need), and
    // every accessor in it is converted to its final mesh array at once
    // (ready, owned here until the primitive takes it): no view is kept,
    // copied, or decoded twice. Anything else keeps the path above.
    std::vector<int> acc_role, acc_uses, acc_state;  // per accessor; state 0 not yet, 1 converted, 2 left to read()
    // A pre view's arrays are also prepared where they are converted (on
    // the pool: prepare_internal.h), so that a primitive whose arrays all
    // were is added as it is, not prepared again on one core: per
    // accessor, what that step found (written only by the task that
    // converts it, read after), the mesh whose name its messages give, and
    // for an index list its primitive's vertex count.
    struct Prep {
        int state = 0;  // 0 not prepared, 1 prepared, 2 failed (err)
        mr_error err;
        double shift[3] = {0, 0, 0};  // positions: what recentring moved into the origin
        float bmin[3], bmax[3];
        // Filled by fill_post, each half of the array into its own slot:
        // positions' bounds, normals already unit, an index list's largest.
        bool chunked = false;  // set before the tasks run
        bool bad[2] = {false, false};  // a non-finite value seen
        double lo[2][3], hi[2][3];
        uint32_t imax[2] = {0, 0};
    };
    std::vector<Prep> acc_prep;
    std::vector<int> acc_mesh;
    std::vector<uint32_t> acc_nv;
    std::vector<char> view_pre;
    std::vector<std::vector<int>> view_readers;  // pre views -> their accessors
    std::map<int, void *> ready;                 // accessor -> malloc'd float or uint32 array, or part of a scene block
    // The last pre view to decode may leave its 32-bit index lists in the
    // scratch itself (Convert::slices: pages not faulted twice), so the
    // scratch is malloc'd.
    unsigned char *scratch = nullptr;
    size_t scratch_n = 0, scratch_need = 0;
    std::vector<char> view_decoded;
    size_t pre_left = 0;  // pre views with readers not yet decoded
    std::vector<const char *> globs;
    std::vector<std::pair<int32_t, int32_t>> mesh_map;  // glTF mesh -> (first, count); first -2: not yet
    std::vector<int32_t> tex_map;                        // glTF texture -> scene texture; -2: not yet
    std::string warn;

    void (*progress)(void *, const char *, double) = nullptr;
    void *progress_user = nullptr;

    // Meshes read but not yet in the scene: a big one is prepared
    // (mr_mesh_prepare: its checks, recentring and normals, a third of a
    // plain file's load) on the pool while the next primitive is read, and
    // all are added in file order (flush). mesh_total counts the added and
    // the pending: the index the next mesh will get. A node whose meshes are
    // still pending is added without them and given them once they are in
    // (node_fix: node, first mesh, count).
    struct Pending {
        MeshGuard g;
        Pool::Task task;
        bool inline_done = false;  // prepared on the loading thread, not a task
        bool ok = false;
        mr_error err;
    };
    std::deque<std::unique_ptr<Pending>> pending;
    int32_t mesh_total = 0;
    std::vector<std::array<int32_t, 3>> node_fix;
    static const uint32_t k_async_vertices = 16384;
    Pool &pool;  // shut down first in ~Loader, before anything its tasks touch goes

    Loader(const tinygltf::Model &model, mr_scene *scene, Source &source, Pool &p)
        : m(model), s(scene), src(source), pool(p) {}
    ~Loader() {
        pool.shutdown();  // first: no task runs while what they touch goes
        for (auto &kv : ready) release(kv.second);
        std::free(scratch);
    }
    Loader(const Loader &) = delete;
    Loader &operator=(const Loader &) = delete;

    // ------------------------------------------------ bytes of bufferViews

    // A number in an extension object; false if absent.
    static bool ext_num(const tinygltf::Value &o, const char *key, double *out) {
        if (!o.Has(key)) return false;
        const tinygltf::Value &v = o.Get(key);
        if (!v.IsNumber()) return false;
        *out = v.GetNumberAsDouble();
        return std::isfinite(*out);
    }

    // One meshopt view's stream as checked, ready to decode.
    struct Decode {
        int bvi = -1;
        const unsigned char *in = nullptr;
        size_t n = 0, cnt = 0, st = 0, out_n = 0;
        int mode = 0;    // 0 ATTRIBUTES, 1 TRIANGLES, 2 INDICES
        int filter = 0;  // 0 NONE, 1 OCTAHEDRAL, 2 QUATERNION, 3 EXPONENTIAL
        unsigned char *out = nullptr;  // batch_decode's buffer (malloc'd)
        int rc = 0;
    };

    // Checks bufferView bvi's EXT_meshopt_compression object; throws with
    // the reason.
    Decode decode_plan(int bvi, const tinygltf::Value &x) const {
        const tinygltf::BufferView &bv = m.bufferViews[(size_t)bvi];
        double buf = -1, off = 0, len = -1, stride = 0, count = -1;
        if (!x.IsObject() || !ext_num(x, "buffer", &buf) || !ext_num(x, "byteLength", &len) ||
            !ext_num(x, "byteStride", &stride) || !ext_num(x, "count", &count) || !x.Has("mode") ||
            !x.Get("mode").IsString())
            fail(MR_ERR_PARSE, "bufferView %d: EXT_meshopt_compression needs buffer, byteLength, byteStride, count and mode",
                 bvi);
        if (x.Has("byteOffset") && !ext_num(x, "byteOffset", &off))
            fail(MR_ERR_PARSE, "bufferView %d: EXT_meshopt_compression byteOffset is not a number", bvi);
        const std::string mode = x.Get("mode").Get<std::string>();
        const std::string filter = x.Has("filter") && x.Get("filter").IsString() ? x.Get("filter").Get<std::string>() : "NONE";
        if (!(buf >= 0 && buf < (double)src.bufs.size()) || !(off >= 0 && off <= 9e15) || !(len >= 0 && len <= 9e15) ||
            !(count >= 0 && count <= 9e15) || !(stride >= 1 && stride <= 256))
            fail(MR_ERR_PARSE, "bufferView %d: EXT_meshopt_compression has an out-of-range buffer, offset, length, stride or count",
                 bvi);
        const BufRef &b = src.bufs[(size_t)buf];
        Decode d;
        d.bvi = bvi;
        size_t o = (size_t)off;
        d.n = (size_t)len;
        d.st = (size_t)stride;
        d.cnt = (size_t)count;
        if (b.fallback || !b.p || o > b.n || d.n > b.n - o)
            fail(MR_ERR_PARSE, "bufferView %d: its meshopt stream lies outside buffer %d", bvi, (int)buf);
        // Never allocate what the stream cannot hold: meshopt's codecs expand
        // at most 64:1 (vertex), 12:1 (triangles) or 4:1 (sequences), so a
        // lying count fails here in bounded memory.
        if (d.cnt > SIZE_MAX / d.st || d.cnt * d.st > 64 * d.n + 65536)
            fail(MR_ERR_PARSE, "bufferView %d: meshopt count %zu x stride %zu is more than its %zu-byte stream can hold", bvi,
                 d.cnt, d.st, d.n);
        d.out_n = d.cnt * d.st;
        if (bv.byteLength > d.out_n)
            fail(MR_ERR_PARSE, "bufferView %d: byteLength %zu is more than its meshopt data decodes to (%zu)", bvi,
                 bv.byteLength, d.out_n);
        d.in = b.p + o;
        if (mode == "ATTRIBUTES") {
            if (d.st % 4 != 0) fail(MR_ERR_PARSE, "bufferView %d: meshopt ATTRIBUTES stride %zu is not a multiple of 4", bvi, d.st);
            if (filter == "OCTAHEDRAL") {
                if (d.st != 4 && d.st != 8) fail(MR_ERR_PARSE, "bufferView %d: OCTAHEDRAL filter needs stride 4 or 8", bvi);
                d.filter = 1;
            } else if (filter == "QUATERNION") {
                if (d.st != 8) fail(MR_ERR_PARSE, "bufferView %d: QUATERNION filter needs stride 8", bvi);
                d.filter = 2;
            } else if (filter == "EXPONENTIAL") {
                d.filter = 3;
            } else if (filter != "NONE") {
                fail(MR_ERR_UNSUPPORTED, "bufferView %d: meshopt filter %s (not supported)", bvi, filter.c_str());
            }
        } else if (mode == "TRIANGLES" || mode == "INDICES") {
            if (d.st != 2 && d.st != 4) fail(MR_ERR_PARSE, "bufferView %d: meshopt %s stride must be 2 or 4", bvi, mode.c_str());
            if (mode == "TRIANGLES" && d.cnt % 3 != 0)
                fail(MR_ERR_PARSE, "bufferView %d: meshopt TRIANGLES count %zu is not a multiple of 3", bvi, d.cnt);
            d.mode = mode == "TRIANGLES" ? 1 : 2;
        } else {
            fail(MR_ERR_UNSUPPORTED, "bufferView %d: meshopt mode %s (not supported)", bvi, mode.c_str());
        }
        return d;
    }

    // Decodes d into out (every byte written, or an error): the decoder's
    // return code. Never throws: runs on a second thread too.
    static int decode_run(const Decode &d, unsigned char *out) {
        int rc = decode_stream(d, out);
        if (rc == 0) decode_filter(d, out, 0, d.cnt);
        return rc;
    }
    static int decode_stream(const Decode &d, unsigned char *out) {
        if (d.mode == 1) return meshopt_decodeIndexBuffer(out, d.cnt, d.st, d.in, d.n);
        if (d.mode == 2) return meshopt_decodeIndexSequence(out, d.cnt, d.st, d.in, d.n);
        return meshopt_decodeVertexBuffer(out, d.cnt, d.st, d.in, d.n);
    }
    // The filter of elements [first, first + count): each element on its
    // own, so a view's filter can be split between the cores.
    static void decode_filter(const Decode &d, unsigned char *out, size_t first, size_t count) {
        unsigned char *p = out + first * d.st;
        if (d.mode != 0 || count == 0) return;
        if (d.filter == 1) meshopt_decodeFilterOct(p, count, d.st);
        else if (d.filter == 2) meshopt_decodeFilterQuat(p, count, d.st);
        else if (d.filter == 3) meshopt_decodeFilterExp(p, count, d.st);
    }

    void decode_check(const Decode &d) const {
        static const char *const names[3] = {"ATTRIBUTES", "TRIANGLES", "INDICES"};
        if (d.rc != 0)
            fail(MR_ERR_PARSE, "bufferView %d: malformed meshopt %s stream (decoder error %d)", d.bvi, names[d.mode], d.rc);
    }

    // Pre views (see view_pre) decode on both cores: from the one asked
    // for on, the next ones primitives will ask for (pre_order) join a batch
    // of up to batch_limit decoded bytes; each view of the batch is decoded,
    // converted into its accessors' arrays and those prepared, by one task
    // on the pool (its index list, where it can, keeps the decoded buffer
    // itself). A view whose object is wrong stays out of the batch and fails
    // when asked for, as before.
    std::vector<int> pre_order;  // pre views, in the order primitives first read them
    std::vector<size_t> pre_rank;  // view -> its place in pre_order
    size_t pre_pos = 0;
    size_t alone_before = 0;  // views before this place in pre_order decode alone (too few bytes ahead)
    static const size_t batch_min = (size_t)4 << 20, batch_limit = (size_t)256 << 20;

    bool batch_decode(int bvi) {
        if (std::thread::hardware_concurrency() < 2 || pre_rank[(size_t)bvi] < alone_before) return false;
        std::vector<Decode> batch;
        size_t bytes = 0;
        auto add = [&](int v) {
            auto x = m.bufferViews[(size_t)v].extensions.find("EXT_meshopt_compression");
            batch.push_back(decode_plan(v, x->second));  // throws for bvi only (see below)
            bytes += batch.back().out_n;
        };
        add(bvi);
        while (pre_pos < pre_order.size() && pre_order[pre_pos] != bvi && view_decoded[(size_t)pre_order[pre_pos]]) pre_pos++;
        size_t k = pre_pos;
        for (; k < pre_order.size() && bytes < batch_limit; k++) {
            int v = pre_order[k];
            if (v == bvi || view_decoded[(size_t)v] || view_readers[(size_t)v].empty()) continue;
            try {
                add(v);
            } catch (const Fail &) {
                continue;  // decoded alone when asked for, to fail there
            }
            if (bytes > batch_limit) {  // over: this one waits for the next batch
                bytes -= batch.back().out_n;
                batch.pop_back();
                break;
            }
        }
        if (batch.size() < 2 || bytes < batch_min) {
            // What is left up to k is too little too: no view there looks
            // ahead again (else a file of many small views would cost the
            // square of their count).
            alone_before = k;
            return false;
        }
        struct Free {
            std::vector<Decode> &b;
            ~Free() {
                for (Decode &d : b) std::free(d.out);
            }
        } guard{batch};
        for (Decode &d : batch) d.out = xmalloc<unsigned char>(d.out_n ? d.out_n : 1);
        // Each view is planned here (its arrays allocated: plan_convert
        // needs only the buffer's address), then decoded and converted by
        // one task on the pool, largest first, while this thread runs tasks
        // too: both cores decode and convert, and nothing waits on one
        // thread's conversions. Measured on the 2M-triangle unique factory
        // (gltfpack -c): one thread decoding while this one converted left
        // this one waiting on the largest view, then the helper idle.
        std::vector<size_t> order(batch.size());
        for (size_t k = 0; k < order.size(); k++) order[k] = k;
        std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return batch[a].out_n > batch[b].out_n; });
        std::vector<Convert> conv(batch.size());
        for (size_t b = 0; b < batch.size(); b++) {
            conv[b] = plan_convert(batch[b].bvi, batch[b].out, m.bufferViews[(size_t)batch[b].bvi].byteLength, &batch[b].out);
            // An OCTAHEDRAL view read only as normals, each element's own
            // first three components: filtered while converted (oct_fill),
            // one pass instead of two.
            Decode &d = batch[b];
            bool oct = d.filter == 1 && conv[b].slices.empty() && conv[b].jobs.size() == view_readers[(size_t)d.bvi].size();
            for (const Job &j : conv[b].jobs)
                oct = oct && acc_role[(size_t)j.v.index] == k_role_normal && j.n == 3 && j.v.normalized && j.v.ncomp >= 3 &&
                      j.v.stride == d.st && m.accessors[(size_t)j.v.index].byteOffset % d.st == 0 &&
                      ((j.v.comp == TINYGLTF_COMPONENT_TYPE_BYTE && d.st == 4) || (j.v.comp == TINYGLTF_COMPONENT_TYPE_SHORT && d.st == 8));
            if (oct) {
                for (Job &j : conv[b].jobs) j.oct = true;
                d.filter = 0;
            }
            for (const Job &j : conv[b].jobs) acc_prep[(size_t)j.v.index].chunked = true;
        }
        // Three tasks a view: its stream's decoding, then the two halves of
        // what follows it (per element: the filter's leftovers aside, its
        // arrays filled and checked), queued behind the decodings not yet
        // started. So a core that ends a decoding starts the next one and
        // the halves fill the gaps: no core waits on the other's decoding
        // while one is queued. Measured on the 2M unique factory (gltfpack
        // -c): with each view's halves run as soon as it was decoded, a core
        // sat idle 2.3 of 19 ms while the last one decoded. The half that
        // ends last gives the arrays their prepare step (which needs both
        // halves' bounds) and frees the buffer.
        struct Stage {
            Pool::Task decode, half[2];
            bool queued = false;  // the halves were submitted (read after wait(decode))
            std::atomic<int> left{2};
        };
        std::deque<Stage> st(batch.size());
        struct Wait {  // every task ends before batch, conv and the buffers go
            Pool &p;
            std::deque<Stage> &st;
            size_t n = 0;
            void all() {
                for (size_t k = 0; k < n; k++) {
                    p.wait(st[k].decode);
                    if (st[k].queued) {
                        p.wait(st[k].half[0]);
                        p.wait(st[k].half[1]);
                    }
                }
            }
            ~Wait() { all(); }
        } wait{pool, st};
        for (size_t k = 0; k < order.size(); k++) {
            const size_t b = order[k];
            Stage &g = st[k];
            g.decode.fn = [&, b] {
                Decode &d = batch[b];
                d.rc = decode_stream(d, d.out);
                if (d.rc != 0) return;
                decode_filter(d, d.out, 0, d.filter ? d.cnt : 0);  // whole: a half's arrays may read the other's elements
                g.queued = true;
                pool.submit(&g.half[0]);
                pool.submit(&g.half[1]);
            };
            for (int h = 0; h < 2; h++)
                g.half[h].fn = [&, b, h] {
                    Decode &d = batch[b];
                    const std::vector<Job> &jobs = conv[b].jobs;
                    const std::vector<int> &slices = conv[b].slices;
                    for (const Job &j : jobs) fill_post(j, h ? j.v.count / 2 : 0, h ? j.v.count - j.v.count / 2 : j.v.count / 2, h);
                    for (size_t k = (size_t)h; k < slices.size(); k += 2) {
                        const tinygltf::Accessor &a = m.accessors[(size_t)slices[k]];
                        prep_array(slices[k], d.out + a.byteOffset, a.count);
                    }
                    if (--g.left != 0) return;
                    for (const Job &j : jobs) prep_array(j.v.index, j.out, j.v.count);
                    if (slices.empty()) {  // its bytes are all converted: gone now, not at the batch's end
                        std::free(d.out);
                        d.out = nullptr;
                    }
                };
            pool.submit(&g.decode);
            wait.n = k + 1;
        }
        wait.all();
        Decode *failed = nullptr;
        for (size_t b = 0; b < batch.size(); b++) {
            Decode &d = batch[b];
            if (d.rc != 0) {
                unplan_convert(conv[b]);
                if (d.bvi == bvi) failed = &d;
                continue;  // the others fail when asked for, decoded again
            }
            src.consumed(d.n);
            finish_convert(conv[b]);
        }
        if (failed) decode_check(*failed);  // the one asked for: its error now
        // Free frees each buffer, unless the scene took it (slices).
        return true;
    }

    // EXT_meshopt_compression: the bufferView's bytes decoded from its
    // compressed stream (once; views are shared by accessors).
    const unsigned char *meshopt_view(int bvi, const tinygltf::Value &x) {
        auto it = meshopt.find(bvi);
        if (it != meshopt.end()) return it->second.get();
        const bool pre = (size_t)bvi < view_pre.size() && view_pre[(size_t)bvi];
        if (pre && !view_decoded[(size_t)bvi] && !view_readers[(size_t)bvi].empty() && batch_decode(bvi)) {
            // Its accessors are converted (ready: accessor_view takes them
            // and reads no bytes), unless one is left to read(): then its
            // bytes are decoded again below, as before.
            bool left = false;
            for (int a : view_readers[(size_t)bvi]) left = left || acc_state[(size_t)a] == 2;
            static const unsigned char none = 0;
            if (!left) return &none;
        }
        const tinygltf::BufferView &bv = m.bufferViews[(size_t)bvi];
        Decode d = decode_plan(bvi, x);
        // Not zeroed: the decoder writes every byte, or fails.
        std::unique_ptr<unsigned char[]> own;
        if (pre && (scratch_n < d.out_n || !scratch)) {
            std::free(scratch);
            scratch = nullptr;
            scratch_n = std::max(std::max(d.out_n, scratch_need), (size_t)1);
            scratch = xmalloc<unsigned char>(scratch_n);
        } else if (!pre) {
            own.reset(new unsigned char[d.out_n ? d.out_n : 1]);
        }
        unsigned char *out = pre ? scratch : own.get();
        d.rc = decode_run(d, out);
        decode_check(d);
        src.consumed(d.n);
        if (pre) {
            preconvert(bvi, out, bv.byteLength, nullptr);
            return out;
        }
        return meshopt.emplace(bvi, std::move(own)).first->second.get();
    }

    // The bytes of bufferView bvi, bounds-checked; *len gets its byteLength.
    const unsigned char *view_bytes(int bvi, size_t *len) {
        if (bvi < 0 || (size_t)bvi >= m.bufferViews.size()) fail(MR_ERR_PARSE, "bufferView %d does not exist", bvi);
        const tinygltf::BufferView &bv = m.bufferViews[(size_t)bvi];
        *len = bv.byteLength;
        auto x = bv.extensions.find("EXT_meshopt_compression");
        if (x != bv.extensions.end()) return meshopt_view(bvi, x->second);
        if (bv.buffer < 0 || (size_t)bv.buffer >= src.bufs.size())
            fail(MR_ERR_PARSE, "bufferView %d refers to a missing buffer", bvi);
        const BufRef &b = src.bufs[(size_t)bv.buffer];
        if (b.fallback)
            fail(MR_ERR_PARSE, "bufferView %d reads meshopt fallback buffer %d, which has no data", bvi, bv.buffer);
        if (bv.byteOffset > b.n || bv.byteLength > b.n - bv.byteOffset)
            fail(MR_ERR_PARSE, "bufferView %d (offset %zu, %zu bytes) lies outside its buffer (%zu bytes)", bvi,
                 bv.byteOffset, bv.byteLength, b.n);
        return b.p + bv.byteOffset;
    }

    // ------------------------------------------------------ accessors

    // The accessor of a primitive attribute or its indices has been read:
    // its decoded meshopt view goes once no other primitive needs it.
    void done(int accessor) {
        if (accessor < 0 || (size_t)accessor >= m.accessors.size()) return;
        int bv = m.accessors[(size_t)accessor].bufferView;
        if (bv < 0 || (size_t)bv >= view_uses.size()) return;
        if (--view_uses[(size_t)bv] <= 0) meshopt.erase(bv);
    }

    void count_view_uses() {
        view_uses.assign(m.bufferViews.size(), 0);
        acc_role.assign(m.accessors.size(), k_role_none);
        acc_uses.assign(m.accessors.size(), 0);
        acc_state.assign(m.accessors.size(), 0);
        acc_prep.assign(m.accessors.size(), Prep());
        acc_mesh.assign(m.accessors.size(), -1);
        acc_nv.assign(m.accessors.size(), 0);
        int use_mesh = -1;
        uint32_t use_nv = 0;
        auto use = [&](int a, int role) {
            if (a < 0 || (size_t)a >= m.accessors.size()) return;
            acc_mesh[(size_t)a] = use_mesh;
            if (role == k_role_index) acc_nv[(size_t)a] = use_nv;
            int &r = acc_role[(size_t)a];
            r = r == k_role_none || r == role ? role : k_role_mixed;
            acc_uses[(size_t)a]++;
            int bv = m.accessors[(size_t)a].bufferView;
            if (bv >= 0 && (size_t)bv < view_uses.size()) view_uses[(size_t)bv]++;
        };
        std::vector<char> other(m.bufferViews.size(), 0);  // read by something else too
        auto mark = [&](int bv) {
            if (bv >= 0 && (size_t)bv < other.size()) other[(size_t)bv] = 1;
        };
        for (size_t mi = 0; mi < m.meshes.size(); mi++)
            for (size_t pi = 0; pi < m.meshes[mi].primitives.size(); pi++) {
                const tinygltf::Primitive &p = m.meshes[mi].primitives[pi];
                const int roles[3] = {k_role_position, k_role_normal, k_role_uv};
                int ri = 0;
                use_mesh = (int)mi;
                auto pit = p.attributes.find("POSITION");
                use_nv = 0;
                if (pit != p.attributes.end() && pit->second >= 0 && (size_t)pit->second < m.accessors.size() &&
                    m.accessors[(size_t)pit->second].count <= UINT32_MAX)
                    use_nv = (uint32_t)m.accessors[(size_t)pit->second].count;
                for (const char *k : {"POSITION", "NORMAL", "TEXCOORD_0"}) {
                    auto it = p.attributes.find(k);
                    if (it != p.attributes.end()) use(it->second, roles[ri]);
                    ri++;
                }
                auto moved = src.moved_indices.find(std::make_pair((int)mi, (int)pi));
                use(moved != src.moved_indices.end() ? moved->second : p.indices, k_role_index);
                auto dx = p.extensions.find("KHR_draco_mesh_compression");
                if (dx != p.extensions.end() && dx->second.IsObject() && dx->second.Has("bufferView") &&
                    dx->second.Get("bufferView").IsNumber())
                    mark(dx->second.Get("bufferView").GetNumberAsInt());
            }
        for (const tinygltf::Image &im : m.images) mark(im.bufferView);
        for (const tinygltf::Accessor &a : m.accessors)
            if (a.sparse.isSparse) {
                mark(a.bufferView);
                mark(a.sparse.indices.bufferView);
                mark(a.sparse.values.bufferView);
            }
        view_pre.assign(m.bufferViews.size(), 0);
        view_readers.assign(m.bufferViews.size(), std::vector<int>());
        for (size_t bi = 0; bi < m.bufferViews.size(); bi++) {
            auto x = m.bufferViews[bi].extensions.find("EXT_meshopt_compression");
            view_pre[bi] = x != m.bufferViews[bi].extensions.end() && !other[bi];
        }
        for (size_t ai = 0; ai < m.accessors.size(); ai++) {
            int bv = m.accessors[ai].bufferView;
            if (bv < 0 || (size_t)bv >= view_pre.size() || !view_pre[(size_t)bv] || acc_uses[ai] == 0) continue;
            if (acc_uses[ai] != 1 || acc_role[ai] == k_role_mixed) view_pre[(size_t)bv] = 0;  // shared: read() copies
            else view_readers[(size_t)bv].push_back((int)ai);
        }
        scratch_need = 0;
        pre_left = 0;
        view_decoded.assign(m.bufferViews.size(), 0);
        for (size_t bi = 0; bi < m.bufferViews.size(); bi++) {
            if (!view_pre[bi]) {
                view_readers[bi].clear();
                continue;
            }
            if (!view_readers[bi].empty()) pre_left++;
            // The largest decoded size of these views: the scratch is
            // allocated once. Checked in meshopt_view; a lie only grows this
            // up to its stream's 64:1.
            const tinygltf::Value &x = m.bufferViews[bi].extensions.find("EXT_meshopt_compression")->second;
            double cnt = 0, st = 0, len = 0;
            if (x.IsObject() && ext_num(x, "count", &cnt) && ext_num(x, "byteStride", &st) && ext_num(x, "byteLength", &len) &&
                cnt >= 0 && st >= 1 && st <= 256 && len >= 0 && cnt * st <= 64 * len + 65536 && cnt * st < 4.0e9)
                scratch_need = std::max(scratch_need, (size_t)(cnt * st));
        }
        // The order primitives will ask for pre views (batch_decode reads
        // ahead in it).
        pre_order.clear();
        pre_rank.assign(m.bufferViews.size(), SIZE_MAX);
        pre_pos = 0;
        alone_before = 0;
        std::vector<char> listed(m.bufferViews.size(), 0);
        auto list = [&](int a) {
            if (a < 0 || (size_t)a >= m.accessors.size()) return;
            int bv = m.accessors[(size_t)a].bufferView;
            if (bv < 0 || (size_t)bv >= view_pre.size() || !view_pre[(size_t)bv] || listed[(size_t)bv] ||
                view_readers[(size_t)bv].empty())
                return;
            listed[(size_t)bv] = 1;
            pre_rank[(size_t)bv] = pre_order.size();
            pre_order.push_back(bv);
        };
        for (size_t mi = 0; mi < m.meshes.size(); mi++)
            for (size_t pi = 0; pi < m.meshes[mi].primitives.size(); pi++) {
                const tinygltf::Primitive &p = m.meshes[mi].primitives[pi];
                for (const char *k : {"POSITION", "NORMAL", "TEXCOORD_0"}) {
                    auto it = p.attributes.find(k);
                    if (it != p.attributes.end()) list(it->second);
                }
                auto moved = src.moved_indices.find(std::make_pair((int)mi, (int)pi));
                list(moved != src.moved_indices.end() ? moved->second : p.indices);
            }
    }

    // Byte window of accessor a in a view of len bytes at p, as
    // accessor_view checks it; false where it would fail (read() then says
    // why, in the primitive that reads it).
    bool window(int a, const unsigned char *p, size_t len, View *out) const {
        const tinygltf::Accessor &acc = m.accessors[(size_t)a];
        int csize = component_size(acc.componentType), ncomp = type_components(acc.type);
        if (csize == 0 || ncomp == 0 || acc.count == 0 || acc.sparse.isSparse) return false;
        size_t elem = (size_t)csize * (size_t)ncomp;
        const tinygltf::BufferView &bv = m.bufferViews[(size_t)acc.bufferView];
        size_t stride = bv.byteStride ? bv.byteStride : elem;
        if (stride < elem || acc.byteOffset > len || elem > len - acc.byteOffset ||
            (acc.count - 1) > (len - acc.byteOffset - elem) / stride)
            return false;
        *out = View{p + acc.byteOffset, stride, acc.count, acc.componentType, ncomp, acc.normalized, a, false};
        return true;
    }

    // One accessor of a pre view to convert: its window, its component count
    // and its array (allocated, in ready; see plan_one).
    struct Job {
        View v;
        int n;
        void *out;
        bool oct = false;  // unfiltered OCTAHEDRAL normals: decoded straight to unit floats (oct_fill)
    };

    // A pre view decoded (or to be decoded) at p: each of its accessors
    // becomes the array its primitive takes (take), in the layout
    // primitive() would read it in; any that primitive() would refuse or
    // warn about is left to it (read again from a fresh decode, to fail or
    // warn as it does). own: the malloc'd buffer at p that its 32-bit index
    // lists may stay in (Convert::slices; then *own becomes NULL); NULL:
    // the scratch, when this is the last pre view (see scratch).
    // plan_convert allocates the arrays and needs only p's address, so a
    // view is planned before it is decoded; run_jobs fills them from the
    // decoded bytes; finish_convert hands the buffer over.
    struct Convert {
        int bvi = -1;
        std::vector<Job> jobs;
        size_t bytes = 0;
        // 32-bit index lists left where they were decoded: the buffer
        // becomes the scene's (mr_scene_adopt_block) and each list a part
        // of it, no copy, no fresh pages (on the 2M unique factory, gltfpack
        // -c: 14.6 of its 22 MB of indices were copied before).
        std::vector<int> slices;
        size_t slice_bytes = 0, own_n = 0;
        unsigned char **own = nullptr;
    };
    Convert plan_convert(int bvi, const unsigned char *p, size_t len, unsigned char **own) {
        Convert c;
        c.bvi = bvi;
        bool last = false;
        if (!view_decoded[(size_t)bvi] && !view_readers[(size_t)bvi].empty()) {
            view_decoded[(size_t)bvi] = 1;
            last = --pre_left == 0;
        }
        if (!own && last && p == scratch) own = &scratch;
        if (own && *own == p)
            for (int a : view_readers[(size_t)bvi]) {
                View v;
                if (acc_state[(size_t)a] == 0 && acc_role[(size_t)a] == k_role_index && m.accessors[(size_t)a].byteOffset % 4 == 0 &&
                    window(a, p, len, &v) && v.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT && v.ncomp == 1 && v.stride == 4 &&
                    v.count <= UINT32_MAX) {
                    c.slices.push_back(a);
                    c.slice_bytes += v.count * 4;
                }
            }
        // Only where the lists are most of the buffer: it stays whole as
        // long as the scene does.
        if (c.slice_bytes < len - len / 4) {
            c.slices.clear();
            c.slice_bytes = 0;
        }
        bool all = true;
        for (int a : view_readers[(size_t)bvi])
            if (std::find(c.slices.begin(), c.slices.end(), a) == c.slices.end()) {
                Job j;
                if (plan_one(a, p, len, &j)) {
                    c.jobs.push_back(j);
                    c.bytes += j.v.count * (size_t)j.n * 4;
                } else {
                    all = all && acc_state[(size_t)a] == 1;
                }
            }
        if (!c.slices.empty() && !all) {
            // Some accessor is left to read(), which reads this view's
            // bytes after us: the buffer stays, the index lists are copied.
            for (int a : c.slices) {
                Job j;
                if (plan_one(a, p, len, &j)) {
                    c.jobs.push_back(j);
                    c.bytes += j.v.count * 4;
                }
            }
            c.slices.clear();
            c.slice_bytes = 0;
        }
        c.own = own;
        c.own_n = len;
        return c;
    }

    void finish_convert(Convert &c) {
        for (const Job &j : c.jobs) {
            src.consumed(j.v.count * j.v.stride);
            acc_state[(size_t)j.v.index] = 1;
        }
        if (c.slices.empty()) return;
        unsigned char **own = c.own;
        if (!mr_scene_adopt_block(s, *own, c.own_n)) throw std::bad_alloc();  // *own still ours: freed as before
        for (int a : c.slices) {
            ready[a] = *own + m.accessors[(size_t)a].byteOffset;
            src.consumed(m.accessors[(size_t)a].count * 4);
            acc_state[(size_t)a] = 1;
        }
        *own = nullptr;
        if (own == &scratch) scratch_n = 0;
    }

    // Frees an array the loader holds, unless it is part of a scene block.
    void release(void *p) { mr_scene_array_free(s, p); }

    // A mesh array. In a big file, one of 64 KiB to 4 MiB is carved from
    // a 32 MiB block of whole huge pages that the scene owns
    // (mr_scene_adopt_block): on its own such an array was a mapping of
    // 4 KiB pages, each fault costing 3.5 times a huge page's per byte
    // (the unpacked 2M factory's 101 meshes: a sixth of its load in
    // faults). The block's tail that no array fits in stays untouched.
    unsigned char *arena = nullptr;
    size_t arena_left = 0;
    template <typename T>
    T *array_alloc(size_t n) {
        static const size_t lo = (size_t)64 << 10, hi = (size_t)4 << 20, block = (size_t)32 << 20;
        if (n > SIZE_MAX / sizeof(T) || src.input_bytes < ((size_t)16 << 20) || n * sizeof(T) < lo || n * sizeof(T) >= hi)
            return xmalloc<T>(n);
        const size_t bytes = (n * sizeof(T) + 63) & ~(size_t)63;
        if (arena_left < bytes) {
            unsigned char *b = xmalloc<unsigned char>(block);
            if (!mr_scene_adopt_block(s, b, block)) {
                std::free(b);
                throw std::bad_alloc();
            }
            arena = b;
            arena_left = block;
        }
        T *p = reinterpret_cast<T *>(arena);
        arena += bytes;
        arena_left -= bytes;
        return p;
    }

    // A planned view whose decoding failed: as if never planned (decoded
    // again, alone, when asked for, to fail there).
    void unplan_convert(const Convert &c) {
        for (int a : view_readers[(size_t)c.bvi]) {
            release(take<void>(a));
            acc_state[(size_t)a] = 0;
        }
        if (view_decoded[(size_t)c.bvi]) {
            view_decoded[(size_t)c.bvi] = 0;
            pre_left++;
        }
    }

    void preconvert(int bvi, const unsigned char *p, size_t len, unsigned char **own) {
        Convert c = plan_convert(bvi, p, len, own);
        run_jobs(c.jobs, c.bytes);
        finish_convert(c);
    }

    // Accessor a's Job, its array allocated (in ready); false if it is left
    // to read() (acc_state 2) or already done.
    bool plan_one(int a, const unsigned char *p, size_t len, Job *j) {
        if (acc_state[(size_t)a] != 0) return false;
        acc_state[(size_t)a] = 2;
        View v;
        if (!window(a, p, len, &v) || v.count > UINT32_MAX) return false;
        const int role = acc_role[(size_t)a];
        int n = 0;
        if (role == k_role_position && position_ok(v)) n = 3;
        else if (role == k_role_normal && normal_ok(v)) n = 3;
        else if (role == k_role_uv && uv_ok(v)) n = 2;
        else if (role == k_role_index && v.ncomp == 1 &&
                 (v.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || v.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                  v.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
            n = 1;
        if (n == 0) return false;
        void *&slot = ready[a];  // owned here before anything can throw
        if (role == k_role_index) slot = array_alloc<uint32_t>(v.count);
        else slot = array_alloc<float>(v.count * (size_t)n);
        *j = Job{v, n, slot};
        return true;
    }

    // Fills the jobs' arrays (read() cannot fail on them: no sparse), the
    // elements split in two halves on a second thread when there are
    // bytes enough to pay for it and a second core.
    void mesh_name(int mi, char out[64]) const {
        if (mi < 0 || (size_t)mi >= m.meshes.size() || m.meshes[(size_t)mi].name.empty()) std::snprintf(out, 64, "mesh_%d", mi);
        else std::snprintf(out, 64, "%s", m.meshes[(size_t)mi].name.c_str());
    }

    // The prepare step of accessor a's converted array (Prep), from what
    // fill_post found in its chunks; on the pool: touches only acc_prep[a]
    // and the array. An index list that kept the decoded buffer (not
    // chunked) is checked here in full. Non-finite normals are left to
    // primitive(), which regenerates them with a warning.
    void prep_array(int a, void *out, size_t count) {
        Prep &p = acc_prep[(size_t)a];
        if (count > UINT32_MAX) return;
        const uint32_t n = (uint32_t)count;
        const int role = acc_role[(size_t)a];
        char name[64];
        mesh_name(acc_mesh[(size_t)a], name);
        if (role == k_role_position && p.chunked) {
            if (p.bad[0] || p.bad[1]) {
                mr_fail(&p.err, MR_ERR_INVALID, "mesh '%s' has a non-finite position", name);
                p.state = 2;
                return;
            }
            double lo[3], hi[3];
            for (int k = 0; k < 3; k++) {
                lo[k] = std::min(p.lo[0][k], p.lo[1][k]);
                hi[k] = std::max(p.hi[0][k], p.hi[1][k]);
            }
            mr_mesh_recentre_within(static_cast<float *>(out), n, lo, hi, p.shift, p.bmin, p.bmax);
            p.state = 1;
        } else if (role == k_role_normal && p.chunked) {
            p.state = p.bad[0] || p.bad[1] ? 0 : 1;
        } else if (role == k_role_index && acc_nv[(size_t)a] > 0) {
            const bool in_range = p.chunked && std::max(p.imax[0], p.imax[1]) < acc_nv[(size_t)a];
            p.state = in_range || mr_mesh_check_indices(static_cast<const uint32_t *>(out), n, acc_nv[(size_t)a], name, &p.err)
                          ? 1
                          : 2;
        }
    }

    // EXT_meshopt_compression's OCTAHEDRAL filter (as its specification
    // gives it) and the conversion to unit floats in one pass: x and y in
    // units of the third component ("one"), z = one - |x| - |y|, folded
    // over for z < 0, then normalised. The filter would round the normal
    // back to 8 or 16 bits first; this keeps it in float.
    template <typename T>
    static void oct_fill(const unsigned char *base, size_t stride, size_t count, float *out) {
        for (size_t i = 0; i < count; i++) {
            T c[3];
            std::memcpy(c, base + i * stride, sizeof c);
            float x = (float)c[0], y = (float)c[1];
            float z = (float)c[2] - std::fabs(x) - std::fabs(y);
            float t = z < 0.0f ? z : 0.0f;
            x += x >= 0.0f ? t : -t;
            y += y >= 0.0f ? t : -t;
            float l2 = x * x + y * y + z * z;
            float inv = l2 > 0.0f ? 1.0f / std::sqrt(l2) : 0.0f;
            if (l2 > 0.0f) {
                out[3 * i] = x * inv;
                out[3 * i + 1] = y * inv;
                out[3 * i + 2] = z * inv;
            } else {  // a zero vector: left so (made the fallback normal by the prepare step)
                out[3 * i] = out[3 * i + 1] = out[3 * i + 2] = 0.0f;
            }
        }
    }

    // fill_job for elements [first, first + count) in chunks small enough
    // to stay in cache, each then given what prep_array would do in a pass
    // of its own over the whole array: positions' bounds and finite check,
    // normals made unit, an index list's largest index; into half h's
    // slots of the accessor's Prep (on the pool: halves run on both cores).
    void fill_post(const Job &j, size_t first, size_t count, int h) {
        Prep &p = acc_prep[(size_t)j.v.index];
        const int role = acc_role[(size_t)j.v.index];
        for (int k = 0; k < 3; k++) {
            p.lo[h][k] = INFINITY;
            p.hi[h][k] = -INFINITY;
        }
        const size_t chunk = 8192;
        for (size_t c = first; c < first + count; c += chunk) {
            const size_t cn = std::min(chunk, first + count - c);
            fill_job(j, c, cn);
            if (role == k_role_position && j.n == 3) {
                if (!mr_mesh_bounds_add(static_cast<float *>(j.out) + 3 * c, cn, p.lo[h], p.hi[h])) p.bad[h] = true;
            } else if (role == k_role_normal && j.n == 3) {
                float *f = static_cast<float *>(j.out) + 3 * c;
                // integers convert to finite floats: only float ones are checked
                const bool finite = j.v.comp != TINYGLTF_COMPONENT_TYPE_FLOAT || mr_floats_finite(f, 3 * cn);
                if (finite) mr_mesh_unit_normals(f, (uint32_t)cn);
                else p.bad[h] = true;
            } else if (role == k_role_index && j.n == 1) {
                const uint32_t *q = static_cast<const uint32_t *>(j.out) + c;
                uint32_t mx = p.imax[h];
                for (size_t i = 0; i < cn; i++) mx = q[i] > mx ? q[i] : mx;
                p.imax[h] = mx;
            }
        }
    }

    static void fill_job(const Job &j, size_t first, size_t count) {
        View v = j.v;
        v.base += first * v.stride;
        v.count = count;
        if (j.oct) {
            float *o = static_cast<float *>(j.out) + first * 3;
            if (v.comp == TINYGLTF_COMPONENT_TYPE_BYTE) oct_fill<int8_t>(v.base, v.stride, count, o);
            else oct_fill<int16_t>(v.base, v.stride, count, o);
        } else if (j.n == 1) read_plain(v, 1, static_cast<uint32_t *>(j.out) + first);
        else read_plain(v, j.n, static_cast<float *>(j.out) + first * (size_t)j.n);
    }

    // half(0) here and half(1) on the pool (ahead of what waits there: the
    // wait runs it here if the helper is busy), or both here when there
    // are too few bytes to pay for a task. Safe from a task too.
    template <typename F>
    void split(F half, size_t bytes) {
        if (bytes < ((size_t)1 << 20)) {
            half(0);
            half(1);
            return;
        }
        Pool::Task t;
        t.fn = [&] { half(1); };
        pool.submit(&t, true);
        half(0);
        pool.wait(t);
    }

    void run_jobs(const std::vector<Job> &jobs, size_t bytes) {
        split([&](int h) {
            for (const Job &j : jobs) fill_job(j, h ? j.v.count / 2 : 0, h ? j.v.count - j.v.count / 2 : j.v.count / 2);
        }, bytes);
    }

    // The converted array of accessor a, now the caller's; NULL if none.
    template <typename T>
    T *take(int a) {
        auto it = ready.find(a);
        if (it == ready.end()) return nullptr;
        T *p = static_cast<T *>(it->second);
        ready.erase(it);
        return p;
    }

    View accessor_view(int idx, const char *what, const char *mesh) {
        if (idx < 0 || (size_t)idx >= m.accessors.size())
            fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d does not exist", mesh, what, idx);
        const tinygltf::Accessor &a = m.accessors[(size_t)idx];
        int csize = component_size(a.componentType), ncomp = type_components(a.type);
        if (csize == 0 || ncomp == 0)
            fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d has an unknown component type or type", mesh, what, idx);
        if (a.count == 0) fail(MR_ERR_INVALID, "mesh '%s': %s accessor %d is empty", mesh, what, idx);
        size_t elem = (size_t)csize * (size_t)ncomp;
        if (a.bufferView < 0) {
            // Zeros (then sparse values) by the specification; a count the
            // file could not describe is a lie, refused before allocating.
            if (a.count > src.input_bytes)
                fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d claims %zu elements without a bufferView, more than the file's %zu bytes could describe",
                     mesh, what, idx, a.count, src.input_bytes);
            return View{nullptr, elem, a.count, a.componentType, ncomp, a.normalized, idx, false};
        }
        if (ready.count(idx)) return View{nullptr, elem, a.count, a.componentType, ncomp, a.normalized, idx, true};
        size_t len = 0;
        const unsigned char *p = view_bytes(a.bufferView, &len);
        // Decoding the view may just have converted this accessor (preconvert).
        if (ready.count(idx)) return View{nullptr, elem, a.count, a.componentType, ncomp, a.normalized, idx, true};
        const tinygltf::BufferView &bv = m.bufferViews[(size_t)a.bufferView];
        size_t stride = bv.byteStride ? bv.byteStride : elem;
        if (stride < elem)
            fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d: byteStride %zu is smaller than an element (%zu)", mesh,
                 what, idx, stride, elem);
        // byteOffset + stride*(count-1) + elem <= byteLength, without overflow.
        if (a.byteOffset > len || elem > len - a.byteOffset || (a.count - 1) > (len - a.byteOffset - elem) / stride)
            fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d (%zu elements) runs past the end of bufferView %d", mesh,
                 what, idx, a.count, a.bufferView);
        src.consumed(a.count * stride);
        return View{p + a.byteOffset, stride, a.count, a.componentType, ncomp, a.normalized, idx, false};
    }

    // Element loop for component type C; norm_max > 0: normalised by the
    // specification's rule (signed types clamp at -1).
    template <typename C, typename T>
    static void convert(const View &v, int n, int k_n, T *out, double norm_max) {
        const bool norm = v.normalized && norm_max > 0;
        const double inv = norm ? 1.0 / norm_max : 1.0;
        for (size_t i = 0; i < v.count; i++) {
            const unsigned char *p = v.base + i * v.stride;
            T *q = out + i * (size_t)n;
            for (int k = 0; k < k_n; k++) {
                C c;
                std::memcpy(&c, p + (size_t)k * sizeof(C), sizeof(C));
                double d = (double)c * inv;
                if (norm && std::is_signed<C>::value && d < -1.0) d = -1.0;
                q[k] = (T)d;
            }
            for (int k = k_n; k < n; k++) q[k] = T(0);
        }
    }

#if defined(__SSE2__)
    // Four components of an 8- or 16-bit type at p as 32-bit integers.
    template <typename C>
    static __m128i load4(const unsigned char *p) {
        if (sizeof(C) == 1) {
            int32_t w;
            std::memcpy(&w, p, 4);
            __m128i b = _mm_cvtsi32_si128(w);
            if (std::is_signed<C>::value) {
                b = _mm_unpacklo_epi8(b, b);
                return _mm_srai_epi32(_mm_unpacklo_epi16(b, b), 24);
            }
            const __m128i z = _mm_setzero_si128();
            return _mm_unpacklo_epi16(_mm_unpacklo_epi8(b, z), z);
        }
        __m128i h = _mm_loadl_epi64(reinterpret_cast<const __m128i *>(p));
        if (std::is_signed<C>::value) return _mm_srai_epi32(_mm_unpacklo_epi16(h, h), 16);
        return _mm_unpacklo_epi16(h, _mm_setzero_si128());
    }

    // convert_n's loops with SSE2 for 8- and 16-bit components into
    // floats, two or three per element (quantised positions, normals and
    // texture coordinates: a tenth of a gltfpack file's load CPU, scalar).
    // Each element is read as four components and written as four floats,
    // the extra ones inside the next element (read) or overwritten by it
    // (written): so the last element goes the scalar way. The same values:
    // integers exactly, normalised ones through the same double product
    // and clamp. False where this has no loop for the types.
    template <typename C, typename T, int N>
    static bool convert_sse2(const View &v, T *out, double norm_max) {
        if (!std::is_same<T, float>::value || sizeof(C) > 2 || !std::is_integral<C>::value || (N != 2 && N != 3) ||
            v.count < 2 || v.stride < (4 - N) * sizeof(C))
            return false;
        const unsigned char *p = v.base;
        float *q = reinterpret_cast<float *>(out);
        const size_t last = v.count - 1;
        if (!(v.normalized && norm_max > 0)) {
            for (size_t i = 0; i < last; i++, p += v.stride) _mm_storeu_ps(q + i * N, _mm_cvtepi32_ps(load4<C>(p)));
        } else {
            const __m128d inv = _mm_set1_pd(1.0 / norm_max), lo = _mm_set1_pd(std::is_signed<C>::value ? -1.0 : 0.0);
            for (size_t i = 0; i < last; i++, p += v.stride) {
                __m128i c = load4<C>(p);
                __m128d a = _mm_max_pd(_mm_mul_pd(_mm_cvtepi32_pd(c), inv), lo);
                __m128d b = _mm_max_pd(_mm_mul_pd(_mm_cvtepi32_pd(_mm_shuffle_epi32(c, _MM_SHUFFLE(3, 2, 3, 2))), inv), lo);
                _mm_storeu_ps(q + i * N, _mm_movelh_ps(_mm_cvtpd_ps(a), _mm_cvtpd_ps(b)));
            }
        }
        View tail = v;
        tail.base = p;
        tail.count = 1;
        convert_n_scalar<C, T, N>(tail, out + last * N, norm_max);
        return true;
    }
#endif

    // convert for N components of N: a loop the compiler unrolls (the
    // quantised attributes and 16-bit indices of gltfpack files). Same
    // values: integers convert exactly, normalised ones as above.
    template <typename C, typename T, int N>
    static void convert_n(const View &v, T *out, double norm_max) {
#if defined(__SSE2__)
        if (convert_sse2<C, T, N>(v, out, norm_max)) return;
#endif
        convert_n_scalar<C, T, N>(v, out, norm_max);
    }
    template <typename C, typename T, int N>
    static void convert_n_scalar(const View &v, T *out, double norm_max) {
        const unsigned char *p = v.base;
        if (!(v.normalized && norm_max > 0)) {
            for (size_t i = 0; i < v.count; i++, p += v.stride) {
                C c[N];
                std::memcpy(c, p, sizeof c);
                T *q = out + i * N;
                q[0] = (T)c[0];
                if (N > 1) q[N > 1 ? 1 : 0] = (T)c[N > 1 ? 1 : 0];  // unrolled: N is a constant
                if (N > 2) q[N > 2 ? 2 : 0] = (T)c[N > 2 ? 2 : 0];
            }
            return;
        }
        const double inv = 1.0 / norm_max, lo = std::is_signed<C>::value ? -1.0 : 0.0;
        for (size_t i = 0; i < v.count; i++, p += v.stride) {
            C c[N];
            std::memcpy(c, p, sizeof c);
            T *q = out + i * N;
            q[0] = (T)std::max((double)c[0] * inv, lo);
            if (N > 1) q[N > 1 ? 1 : 0] = (T)std::max((double)c[N > 1 ? 1 : 0] * inv, lo);
            if (N > 2) q[N > 2 ? 2 : 0] = (T)std::max((double)c[N > 2 ? 2 : 0] * inv, lo);
        }
    }

    template <typename C, typename T>
    static void convert_any(const View &v, int n, int k_n, T *out, double norm_max) {
        if (k_n == n && n == 1) convert_n<C, T, 1>(v, out, norm_max);
        else if (k_n == n && n == 2) convert_n<C, T, 2>(v, out, norm_max);
        else if (k_n == n && n == 3) convert_n<C, T, 3>(v, out, norm_max);
        else convert<C>(v, n, k_n, out, norm_max);
    }

    // Reads n components per element into out[count*n] (missing components
    // 0), converting any component type, then applies sparse substitution.
    template <typename T>
    void read(const View &v, int n, T *out, const char *what, const char *mesh) {
        read_plain(v, n, out);
        read_sparse(v, n, out, what, mesh);
    }

    // read's element loops: no sparse values, nothing that can fail.
    template <typename T>
    static void read_plain(const View &v, int n, T *out) {
        const int k_n = std::min(n, v.ncomp);
        if (!v.base) {
            std::fill(out, out + v.count * (size_t)n, T(0));
        } else if (k_n == n && ((v.comp == TINYGLTF_COMPONENT_TYPE_FLOAT && std::is_same<T, float>::value) ||
                                (v.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT && std::is_same<T, uint32_t>::value))) {
            if (v.stride == 4 * (size_t)n) std::memcpy(out, v.base, v.count * v.stride);  // tightly packed
            else
                for (size_t i = 0; i < v.count; i++) std::memcpy(out + i * (size_t)n, v.base + i * v.stride, 4 * (size_t)n);
        } else {
            // One loop per component type: quantised files (gltfpack) must
            // load at least as fast as float ones.
            switch (v.comp) {
            case TINYGLTF_COMPONENT_TYPE_BYTE: convert_any<int8_t>(v, n, k_n, out, 127.0); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: convert_any<uint8_t>(v, n, k_n, out, 255.0); break;
            case TINYGLTF_COMPONENT_TYPE_SHORT: convert_any<int16_t>(v, n, k_n, out, 32767.0); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: convert_any<uint16_t>(v, n, k_n, out, 65535.0); break;
            case TINYGLTF_COMPONENT_TYPE_INT: convert_any<int32_t>(v, n, k_n, out, 0); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: convert_any<uint32_t>(v, n, k_n, out, 0); break;
            default: convert_any<float>(v, n, k_n, out, 0); break;
            }
        }
    }

    template <typename T>
    void read_sparse(const View &v, int n, T *out, const char *what, const char *mesh) {
        const int k_n = std::min(n, v.ncomp), cs = component_size(v.comp);
        const tinygltf::Accessor &a = m.accessors[(size_t)v.index];
        if (!a.sparse.isSparse) return;
        // Sparse: count (index, value) pairs replace elements.
        const auto &sp = a.sparse;
        if (sp.count <= 0 || (size_t)sp.count > v.count)
            fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d: sparse count %d is not in [1, %zu]", mesh, what, v.index,
                 sp.count, v.count);
        size_t cnt = (size_t)sp.count, ilen = 0, vlen = 0;
        int is = component_size(sp.indices.componentType);
        if (sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            sp.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d: sparse indices must be unsigned", mesh, what, v.index);
        const unsigned char *ip = view_bytes(sp.indices.bufferView, &ilen);
        const unsigned char *vp = view_bytes(sp.values.bufferView, &vlen);
        size_t elem = (size_t)cs * (size_t)v.ncomp;
        if (sp.indices.byteOffset < 0 || (size_t)sp.indices.byteOffset > ilen ||
            cnt > (ilen - (size_t)sp.indices.byteOffset) / (size_t)is || sp.values.byteOffset < 0 ||
            (size_t)sp.values.byteOffset > vlen || cnt > (vlen - (size_t)sp.values.byteOffset) / elem)
            fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d: sparse data runs past the end of its bufferViews", mesh, what,
                 v.index);
        ip += sp.indices.byteOffset;
        vp += sp.values.byteOffset;
        for (size_t i = 0; i < cnt; i++) {
            size_t j = (size_t)comp_value(ip + i * (size_t)is, sp.indices.componentType, false);
            if (j >= v.count)
                fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d: sparse index %zu is out of range", mesh, what, v.index, j);
            for (int k = 0; k < k_n; k++)
                out[j * (size_t)n + (size_t)k] = (T)comp_value(vp + i * elem + (size_t)(k * cs), v.comp, v.normalized);
        }
    }


    void report(const char *stage, size_t done, size_t total) {
        if (progress && total > 0) progress(progress_user, stage, (double)done / (double)total);
    }

    void warning(const std::string &w) { warn += w + "\n"; }

    // The "nodes" stage's fraction: of the nodes visited or of the file's
    // bytes read, whichever is further (a few huge meshes, or many nodes);
    // reported when it moved by 1 %.
    double progress_shown = 0;
    size_t nodes_visited = 0;
    void progress_nodes(size_t visited) {
        if (!progress) return;
        nodes_visited = std::max(nodes_visited, visited);
        double f = m.nodes.empty() ? 0 : (double)nodes_visited / (double)m.nodes.size();
        if (src.input_bytes) f = std::max(f, std::min(1.0, (double)src.total_read / (double)src.input_bytes));
        if (f < progress_shown + 0.01) return;
        progress_shown = f;
        progress(progress_user, "nodes", f);
    }

    // Any channel count, 8 or 16 bits -> RGBA8.
    bool image_to_rgba8(const tinygltf::Image &img, mr_image *out, std::string *why) {
        int w = img.width, h = img.height, c = img.component;
        int bytes = img.bits == 16 ? 2 : img.bits == 8 ? 1 : 0;
        if (w <= 0 || h <= 0 || w > k_max_image_side || h > k_max_image_side || c < 1 || c > 4 || bytes == 0) {
            *why = "unsupported image layout";
            return false;
        }
        size_t npx = (size_t)w * (size_t)h;
        if (img.image.size() != npx * (size_t)c * (size_t)bytes) {
            *why = "image data size does not match its dimensions";
            return false;
        }
        mr_error e;
        if (!mr_image_alloc(out, w, h, 4, MR_PIX_U8, &e)) {
            *why = e.msg;
            return false;
        }
        const unsigned char *src = img.image.data();
        uint8_t *dst = static_cast<uint8_t *>(out->data);
        for (size_t i = 0; i < npx; i++) {
            uint8_t ch[4];
            for (int k = 0; k < c; k++) {
                if (bytes == 2) {  // native uint16: keep the high byte
                    uint16_t u;
                    std::memcpy(&u, src + (i * (size_t)c + (size_t)k) * 2, 2);
                    ch[k] = (uint8_t)(u >> 8);
                } else {
                    ch[k] = src[i * (size_t)c + (size_t)k];
                }
            }
            uint8_t *q = dst + 4 * i;
            if (c <= 2) {
                q[0] = q[1] = q[2] = ch[0];
                q[3] = c == 2 ? ch[1] : 255;
            } else {
                q[0] = ch[0];
                q[1] = ch[1];
                q[2] = ch[2];
                q[3] = c == 4 ? ch[3] : 255;
            }
        }
        return true;
    }

    int32_t texture(int ti) {
        if (ti < 0) return -1;
        if ((size_t)ti >= m.textures.size()) {
            warning("texture " + std::to_string(ti) + " does not exist");
            return -1;
        }
        if (tex_map[(size_t)ti] != -2) return tex_map[(size_t)ti];
        tex_map[(size_t)ti] = -1;
        const tinygltf::Texture &t = m.textures[(size_t)ti];
        if (t.source < 0 || (size_t)t.source >= m.images.size()) {
            warning("texture " + std::to_string(ti) + " has no valid image");
            return -1;
        }
        tinygltf::Image img = m.images[(size_t)t.source];
        std::string why;
        if (img.image.empty() && img.bufferView >= 0) {
            // Deferred decode (see image_loader), now with bounds checks.
            try {
                size_t len = 0;
                const unsigned char *bytes = view_bytes(img.bufferView, &len);
                decode_image(bytes, len, &img, &why);
            } catch (const Fail &f) {
                why = "image bufferView lies outside its buffer (" + f.msg + ")";
            }
        } else if (img.image.empty()) {
            why = "image data not available" + (img.uri.empty() ? std::string() : " ('" + img.uri.substr(0, 64) + "')");
        }
        mr_texture tex;
        std::memset(&tex, 0, sizeof tex);
        if (!why.empty() || !image_to_rgba8(img, &tex.image, &why)) {
            warning("image " + std::to_string(t.source) + ": " + why + "; texture ignored");
            return -1;
        }
        if (t.sampler >= 0 && (size_t)t.sampler < m.samplers.size())
            tex.nearest = m.samplers[(size_t)t.sampler].magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
        int32_t idx = mr_scene_add_texture(s, &tex);
        if (idx < 0) {
            mr_image_free(&tex.image);
            throw std::bad_alloc();
        }
        tex_map[(size_t)ti] = idx;
        return idx;
    }

    // KHR_texture_transform as the 2x3 matrix of uv_xform; empty: none.
    std::vector<double> texture_transform(const tinygltf::TextureInfo &ti, const std::string &mat) {
        auto x = ti.extensions.find("KHR_texture_transform");
        if (ti.index < 0 || x == ti.extensions.end() || !x->second.IsObject()) return {};
        const tinygltf::Value &o = x->second;
        double off[2] = {0, 0}, sc[2] = {1, 1}, rot = 0;
        for (int k = 0; k < 2; k++) {
            if (o.Has("offset") && o.Get("offset").IsArray() && o.Get("offset").ArrayLen() == 2 &&
                o.Get("offset").Get(k).IsNumber())
                off[k] = o.Get("offset").Get(k).GetNumberAsDouble();
            if (o.Has("scale") && o.Get("scale").IsArray() && o.Get("scale").ArrayLen() == 2 &&
                o.Get("scale").Get(k).IsNumber())
                sc[k] = o.Get("scale").Get(k).GetNumberAsDouble();
        }
        if (o.Has("rotation") && o.Get("rotation").IsNumber()) rot = o.Get("rotation").GetNumberAsDouble();
        if (!std::isfinite(off[0]) || !std::isfinite(off[1]) || !std::isfinite(sc[0]) || !std::isfinite(sc[1]) ||
            !std::isfinite(rot)) {
            warning("material '" + mat + "': non-finite KHR_texture_transform ignored");
            return {};
        }
        if (o.Has("texCoord")) warning("material '" + mat + "': KHR_texture_transform texCoord ignored (TEXCOORD_0 is used)");
        double c = std::cos(rot), sn = std::sin(rot);
        return {c * sc[0], sn * sc[1], off[0], -sn * sc[0], c * sc[1], off[1]};
    }

    void materials() {
        for (size_t i = 0; i < m.materials.size(); i++) {
            const tinygltf::Material &gm = m.materials[i];
            mr_material mat;
            std::memset(&mat, 0, sizeof mat);
            std::snprintf(mat.name, sizeof mat.name, "%s", gm.name.c_str());
            const std::vector<double> &f = gm.pbrMetallicRoughness.baseColorFactor;
            for (int k = 0; k < 4; k++) {
                double v = f.size() == 4 ? f[(size_t)k] : 1.0;
                // glTF's range; also keeps the float cast defined.
                mat.base_color[k] = std::isfinite(v) ? (float)std::min(1.0, std::max(0.0, v)) : 1.0f;
            }
            mat.base_color_texture = texture(gm.pbrMetallicRoughness.baseColorTexture.index);
            uv_xform.push_back(texture_transform(gm.pbrMetallicRoughness.baseColorTexture, gm.name));
            // glTF's default is single-sided.
            mat.single_sided = !gm.doubleSided;
            if (mr_scene_add_material(s, &mat) < 0) throw std::bad_alloc();
        }
    }

    // Triangle list from a primitive's vertex order (indices or 0..n-1).
    static std::vector<uint32_t> triangulate(std::vector<uint32_t> idx, int mode, const char *mesh) {
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (idx.size() % 3 != 0)
                fail(MR_ERR_INVALID, "mesh '%s': %zu indices is not a multiple of 3", mesh, idx.size());
            return idx;
        }
        std::vector<uint32_t> out;
        if (idx.size() < 3) return out;
        out.reserve((idx.size() - 2) * 3);
        for (size_t i = 0; i + 2 < idx.size(); i++) {
            uint32_t a, b, c;
            if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {  // keeps the winding of even triangles
                a = idx[i];
                b = idx[i + 1 + (i & 1)];
                c = idx[i + 2 - (i & 1)];
            } else {  // fan
                a = idx[i + 1];
                b = idx[i + 2];
                c = idx[0];
            }
            if (a == b || b == c || a == c) continue;  // strip restarts
            out.push_back(a);
            out.push_back(b);
            out.push_back(c);
        }
        return out;
    }

    // KHR_texture_transform of each material's base colour texture, as
    // u' = t[0]*u + t[1]*v + t[2], v' = t[3]*u + t[4]*v + t[5] (offset,
    // rotation, scale: T*R*S by the extension). gltfpack dequantises
    // integer texture coordinates through it.
    std::vector<std::vector<double>> uv_xform;

    static bool is_int8_16(int comp) {
        return comp == TINYGLTF_COMPONENT_TYPE_BYTE || comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
               comp == TINYGLTF_COMPONENT_TYPE_SHORT || comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    }

    // Layouts the specification allows (KHR_mesh_quantization widens them).
    bool position_ok(const View &v) const {
        return v.ncomp == 3 && ((v.comp == TINYGLTF_COMPONENT_TYPE_FLOAT && !v.normalized) || (quantized && is_int8_16(v.comp)));
    }
    bool normal_ok(const View &v) const {
        return v.ncomp == 3 && (v.comp == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                                (quantized && v.normalized &&
                                 (v.comp == TINYGLTF_COMPONENT_TYPE_BYTE || v.comp == TINYGLTF_COMPONENT_TYPE_SHORT)));
    }
    bool uv_ok(const View &v) const {
        return v.ncomp == 2 && (v.comp == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                                (v.normalized && (v.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                                  v.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)) ||
                                (quantized && is_int8_16(v.comp)));
    }

    void check_normals(MeshGuard &g, const char *name, bool renormalise) {
        size_t nv = g.m.vertex_count;
        if (!mr_floats_finite(g.m.normals, nv * 3)) {
            warning(std::string("mesh '") + name + "' has non-finite normals; regenerated");
            release(g.m.normals);
            g.m.normals = nullptr;
            return;
        }
        if (!renormalise) return;
        // Quantised normals are unit only up to their rounding.
        for (size_t i = 0; i < nv; i++) {
            float *q = g.m.normals + 3 * i;
            float l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
            if (l > 0) q[0] /= l, q[1] /= l, q[2] /= l;
        }
    }

    bool check_uvs(MeshGuard &g, const char *name) {
        if (mr_floats_finite(g.m.uvs, (size_t)g.m.vertex_count * 2)) return true;
        warning(std::string("mesh '") + name + "' has non-finite texture coordinates; ignored");
        release(g.m.uvs);
        g.m.uvs = nullptr;
        return false;
    }

    // KHR_draco_mesh_compression: the primitive's geometry from its draco
    // bufferView (the accessors then give only types and counts).
    void draco_primitive(const tinygltf::Primitive &p, const tinygltf::Value &x, const char *name, MeshGuard &g,
                         std::vector<uint32_t> &order) {
        double bvd = -1;
        if (!x.IsObject() || !ext_num(x, "bufferView", &bvd) || !x.Has("attributes") || !x.Get("attributes").IsObject())
            fail(MR_ERR_PARSE, "mesh '%s': KHR_draco_mesh_compression needs a bufferView and attributes", name);
        if (!(bvd >= 0 && bvd < (double)m.bufferViews.size()))
            fail(MR_ERR_PARSE, "mesh '%s': draco bufferView %g does not exist", name, bvd);
        size_t len = 0;
        const unsigned char *bytes = view_bytes((int)bvd, &len);
        char why[256] = "";
        struct Free {
            mr_draco *d;
            ~Free() { mr_draco_free(d); }
        } d{mr_draco_decode(bytes, len, why, sizeof why)};
        if (!d.d) fail(MR_ERR_PARSE, "mesh '%s': bad KHR_draco_mesh_compression data (%s)", name, why);
        src.consumed(len);
        const tinygltf::Value &attrs = x.Get("attributes");
        auto id_of = [&](const char *key) -> int {
            if (!attrs.Has(key)) return -1;
            const tinygltf::Value &v = attrs.Get(key);
            double id = v.IsNumber() ? v.GetNumberAsDouble() : -1;
            if (!(id >= 0 && id < 1e9))
                fail(MR_ERR_PARSE, "mesh '%s': draco attribute id of %s is not a number", name, key);
            return (int)id;
        };
        int pid = id_of("POSITION");
        if (pid < 0) fail(MR_ERR_PARSE, "mesh '%s': draco data without POSITION", name);
        uint32_t nv = mr_draco_points(d.d);
        if (nv == 0) fail(MR_ERR_INVALID, "mesh '%s': draco mesh has no points", name);
        auto pos_it = p.attributes.find("POSITION");
        if (pos_it != p.attributes.end() && pos_it->second >= 0 && (size_t)pos_it->second < m.accessors.size() &&
            m.accessors[(size_t)pos_it->second].count != nv)
            warning(std::string("mesh '") + name + "': draco decoded " + std::to_string(nv) +
                    " points, the POSITION accessor says " + std::to_string(m.accessors[(size_t)pos_it->second].count));
        g.m.vertex_count = nv;
        g.m.positions = array_alloc<float>((size_t)nv * 3);
        if (!mr_draco_attribute(d.d, pid, 3, g.m.positions, why, sizeof why))
            fail(MR_ERR_PARSE, "mesh '%s': POSITION: %s", name, why);
        int nid = id_of("NORMAL");
        if (nid >= 0) {
            g.m.normals = array_alloc<float>((size_t)nv * 3);
            if (!mr_draco_attribute(d.d, nid, 3, g.m.normals, why, sizeof why)) {
                warning(std::string("mesh '") + name + "': NORMAL: " + why + "; regenerated");
                release(g.m.normals);
                g.m.normals = nullptr;
            } else {
                check_normals(g, name, true);
            }
        }
        int tid = id_of("TEXCOORD_0");
        if (tid >= 0) {
            g.m.uvs = array_alloc<float>((size_t)nv * 2);
            if (!mr_draco_attribute(d.d, tid, 2, g.m.uvs, why, sizeof why)) {
                warning(std::string("mesh '") + name + "': TEXCOORD_0: " + why + "; ignored");
                release(g.m.uvs);
                g.m.uvs = nullptr;
            }
        }
        order.resize((size_t)mr_draco_faces(d.d) * 3);
        if (!order.empty()) mr_draco_indices(d.d, order.data());
    }

    void primitive(const tinygltf::Primitive &p, const char *name, int mesh_idx, int prim_idx) {
        int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
        if (mode >= TINYGLTF_MODE_POINTS && mode <= TINYGLTF_MODE_LINE_STRIP) {
            warning(std::string("mesh '") + name + "' primitive " + std::to_string(prim_idx) +
                    ": points/lines skipped");
            return;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
            fail(MR_ERR_PARSE, "mesh '%s' primitive %d: unknown mode %d", name, prim_idx, mode);
        auto pos_it = p.attributes.find("POSITION");
        auto dx = p.extensions.find("KHR_draco_mesh_compression");
        if (pos_it == p.attributes.end() && dx == p.extensions.end()) {
            warning(std::string("mesh '") + name + "' primitive " + std::to_string(prim_idx) +
                    " has no POSITION; skipped");
            return;
        }
        MeshGuard g;
        g.blocks = s;
        std::vector<uint32_t> order;
        bool have_order = false;
        int prep_pos = -1, prep_nrm = -1, prep_idx = -1;  // accessors whose arrays came prepared (Prep)
        if (dx != p.extensions.end()) {
            draco_primitive(p, dx->second, name, g, order);
            have_order = true;
        } else {
            View pv = accessor_view(pos_it->second, "POSITION", name);
            if (!position_ok(pv))
                fail(MR_ERR_PARSE, "mesh '%s': POSITION must be FLOAT VEC3%s", name,
                     quantized ? " or 8/16-bit integer VEC3" : " (integers need KHR_mesh_quantization)");
            if (pv.count > UINT32_MAX) fail(MR_ERR_UNSUPPORTED, "mesh '%s': too many vertices", name);
            uint32_t nv = (uint32_t)pv.count;
            g.m.vertex_count = nv;
            // Each array is read once, into the mesh's own (or taken
            // converted from a decoded meshopt view): no copies.
            if (!(g.m.positions = take<float>(pos_it->second))) {
                g.m.positions = array_alloc<float>((size_t)nv * 3);
                read(pv, 3, g.m.positions, "POSITION", name);
            } else if (acc_prep[(size_t)pos_it->second].state) {
                prep_pos = pos_it->second;
            }
            done(pos_it->second);

            auto nrm_it = p.attributes.find("NORMAL");
            if (nrm_it != p.attributes.end()) {
                View nview = accessor_view(nrm_it->second, "NORMAL", name);
                if (!normal_ok(nview) || nview.count != nv) {
                    release(take<float>(nrm_it->second));
                    warning(std::string("mesh '") + name + "': NORMAL has an unsupported layout; regenerated");
                } else {
                    if (!(g.m.normals = take<float>(nrm_it->second))) {
                        g.m.normals = array_alloc<float>((size_t)nv * 3);
                        read(nview, 3, g.m.normals, "NORMAL", name);
                    } else if (acc_prep[(size_t)nrm_it->second].state) {
                        prep_nrm = nrm_it->second;  // finite and unit already
                    }
                    // Integer normals are finite, and mr_scene_add_mesh
                    // makes every normal unit length: only floats are checked.
                    if (nview.comp == TINYGLTF_COMPONENT_TYPE_FLOAT && prep_nrm < 0) check_normals(g, name, false);
                }
                done(nrm_it->second);
            }
            auto uv_it = p.attributes.find("TEXCOORD_0");
            if (uv_it != p.attributes.end()) {
                View uview = accessor_view(uv_it->second, "TEXCOORD_0", name);
                if (!uv_ok(uview) || uview.count != nv) {
                    release(take<float>(uv_it->second));
                    warning(std::string("mesh '") + name + "': TEXCOORD_0 has an unsupported layout; ignored");
                } else {
                    if (!(g.m.uvs = take<float>(uv_it->second))) {
                        g.m.uvs = array_alloc<float>((size_t)nv * 2);
                        read(uview, 2, g.m.uvs, "TEXCOORD_0", name);
                    }
                }
                done(uv_it->second);
            }
            auto moved = src.moved_indices.find(std::make_pair(mesh_idx, prim_idx));
            const int indices = moved != src.moved_indices.end() ? moved->second : p.indices;
            if (indices >= 0) {
                View iv = accessor_view(indices, "index", name);
                if (iv.ncomp != 1 || (iv.comp != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                      iv.comp != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                                      iv.comp != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
                    fail(MR_ERR_PARSE, "mesh '%s': indices must be unsigned byte/short/int scalars", name);
                if (iv.count > UINT32_MAX) fail(MR_ERR_UNSUPPORTED, "mesh '%s': too many indices", name);
                // A triangle list is the mesh's index array as it is read.
                uint32_t *q = take<uint32_t>(indices);
                if (q && acc_prep[(size_t)indices].state) prep_idx = indices;
                if (mode == TINYGLTF_MODE_TRIANGLES) {
                    g.m.indices = q ? q : array_alloc<uint32_t>(iv.count);
                    g.m.index_count = (uint32_t)iv.count;
                    if (!q) read(iv, 1, g.m.indices, "index", name);
                } else if (q) {
                    order.assign(q, q + iv.count);
                    release(q);
                } else {
                    order.resize(iv.count);
                    read(iv, 1, order.data(), "index", name);
                }
                done(indices);
                have_order = true;
            }
        }
        const uint32_t nv = g.m.vertex_count;
        // A triangle list's indices and every position are checked by
        // mr_mesh_prepare (add_mesh), on the pool for a big mesh: not here too.
        if (!g.m.indices) {
            if (have_order) {
                for (size_t i = 0; i < order.size(); i++)
                    if (order[i] >= nv)
                        fail(MR_ERR_INVALID, "mesh '%s': index %u at position %zu is out of range (%u vertices)", name,
                             order[i], i, nv);
            } else {
                order.resize(nv);
                for (uint32_t i = 0; i < nv; i++) order[i] = i;
            }
            std::vector<uint32_t> tris = triangulate(std::move(order), mode, name);
            if (tris.size() > UINT32_MAX) fail(MR_ERR_UNSUPPORTED, "mesh '%s': too many indices", name);
            g.m.index_count = (uint32_t)tris.size();
            g.m.indices = array_alloc<uint32_t>(tris.size());
            if (!tris.empty()) std::memcpy(g.m.indices, tris.data(), tris.size() * sizeof(uint32_t));
            std::vector<uint32_t>().swap(tris);
        }

        g.m.material = -1;
        if (p.material >= 0) {
            if ((size_t)p.material < m.materials.size() && p.material < s->material_count)
                g.m.material = p.material;
            else
                warning(std::string("mesh '") + name + "' uses missing material " + std::to_string(p.material));
        }
        if (g.m.uvs && g.m.material >= 0 && !uv_xform[(size_t)g.m.material].empty()) {
            const std::vector<double> &t = uv_xform[(size_t)g.m.material];
            for (size_t i = 0; i < nv; i++) {
                double u = g.m.uvs[2 * i], v = g.m.uvs[2 * i + 1];
                g.m.uvs[2 * i] = (float)(t[0] * u + t[1] * v + t[2]);
                g.m.uvs[2 * i + 1] = (float)(t[3] * u + t[4] * v + t[5]);
            }
        }
        if (g.m.uvs) check_uvs(g, name);
        std::snprintf(g.m.name, sizeof g.m.name, "%s", name);
        // Arrays prepared where they were converted: their failures are
        // this mesh's, in mr_mesh_prepare's order; recentred positions
        // move the origin; a triangle list whose every array came prepared
        // is added as it is.
        for (int a : {prep_idx, prep_pos})
            if (a >= 0 && acc_prep[(size_t)a].state == 2) throw Fail{acc_prep[(size_t)a].err.code, acc_prep[(size_t)a].err.msg};
        if (prep_pos >= 0)
            for (int k = 0; k < 3; k++) g.m.origin[k] += acc_prep[(size_t)prep_pos].shift[k];
        const bool prepared = prep_pos >= 0 && prep_nrm >= 0 && g.m.normals && prep_idx >= 0 && mode == TINYGLTF_MODE_TRIANGLES &&
                              g.m.index_count % 3 == 0 && g.m.index_count > 0;
        if (prepared)
            for (int k = 0; k < 3; k++) {
                g.m.bounds_min[k] = acc_prep[(size_t)prep_pos].bmin[k];
                g.m.bounds_max[k] = acc_prep[(size_t)prep_pos].bmax[k];
            }
        add_mesh(&g.m, prepared);  // took the arrays: the guard frees nothing more
    }

    // prepared: every array already went through its prepare step.
    void add_mesh(mr_mesh *mm, bool prepared) {
        std::unique_ptr<Pending> own(new Pending);
        Pending *q = own.get();
        q->g.blocks = s;
        q->g.m = *mm;
        std::memset(mm, 0, sizeof *mm);
        mesh_total++;
        if (prepared) {
            q->g.m.name[sizeof q->g.m.name - 1] = 0;
            q->ok = q->inline_done = true;
            pending.push_back(std::move(own));
        } else if (q->g.m.vertex_count >= k_async_vertices || q->g.m.index_count >= 3 * k_async_vertices) {
            q->task.fn = [q] { q->ok = mr_mesh_prepare(&q->g.m, &q->err); };
            pending.push_back(std::move(own));
            pool.submit(&q->task);
        } else {
            q->ok = mr_mesh_prepare(&q->g.m, &q->err);
            q->inline_done = true;
            pending.push_back(std::move(own));
        }
        flush(false);
    }

    // Adds the pending meshes that are prepared, in order, up to the first
    // that is not (all: waits for each). A mesh that failed fails the load
    // here, as it did when it was read.
    void flush(bool all) {
        while (!pending.empty()) {
            Pending &q = *pending.front();
            if (!q.inline_done) {
                if (all) pool.wait(q.task);
                else if (!pool.is_done(q.task)) return;
            }
            if (!q.ok) throw Fail{q.err.code, q.err.msg};
            mr_error e;
            if (mr_scene_add_prepared_mesh(s, &q.g.m, &e) < 0) throw Fail{e.code, e.msg};
            pending.pop_front();
        }
    }

    // The load failed while meshes were pending: a pending one that failed
    // came first in the file, so its error is the load's.
    void earlier_failure() {
        for (const std::unique_ptr<Pending> &q : pending) {
            if (!q->inline_done) pool.wait(q->task);
            if (!q->ok) throw Fail{q->err.code, q->err.msg};
        }
    }

    std::pair<int32_t, int32_t> mesh(int mi) {
        if (mesh_map[(size_t)mi].first != -2) return mesh_map[(size_t)mi];
        const tinygltf::Mesh &gm = m.meshes[(size_t)mi];
        char name[64];
        mesh_name(mi, name);
        int32_t first = mesh_total;
        for (size_t k = 0; k < gm.primitives.size(); k++) primitive(gm.primitives[k], name, mi, (int)k);
        int32_t count = mesh_total - first;
        progress_nodes(0);
        mesh_map[(size_t)mi] = count > 0 ? std::make_pair(first, count) : std::make_pair(-1, 0);
        return mesh_map[(size_t)mi];
    }

    static bool extras_hidden(const tinygltf::Value &ex) {
        if (!ex.IsObject() || !ex.Has("mrcheck_layer")) return false;
        const tinygltf::Value &v = ex.Get("mrcheck_layer");
        return v.IsString() && v.Get<std::string>() == "hidden";
    }

    mr_dmat4 local_matrix(const tinygltf::Node &n, const char *name) {
        mr_dmat4 l;
        if (!n.matrix.empty()) {
            if (n.matrix.size() != 16) fail(MR_ERR_PARSE, "node '%s': matrix must have 16 numbers", name);
            for (int r = 0; r < 4; r++)
                for (int c = 0; c < 4; c++) l.m[r * 4 + c] = n.matrix[(size_t)(c * 4 + r)];  // glTF is column-major
        } else {
            double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, sc[3] = {1, 1, 1};
            if (!n.translation.empty()) {
                if (n.translation.size() != 3) fail(MR_ERR_PARSE, "node '%s': translation must have 3 numbers", name);
                for (int k = 0; k < 3; k++) t[k] = n.translation[(size_t)k];
            }
            if (!n.rotation.empty()) {
                if (n.rotation.size() != 4) fail(MR_ERR_PARSE, "node '%s': rotation must have 4 numbers", name);
                for (int k = 0; k < 4; k++) q[k] = n.rotation[(size_t)k];
            }
            if (!n.scale.empty()) {
                if (n.scale.size() != 3) fail(MR_ERR_PARSE, "node '%s': scale must have 3 numbers", name);
                for (int k = 0; k < 3; k++) sc[k] = n.scale[(size_t)k];
            }
            for (double v : q)
                if (!std::isfinite(v)) fail(MR_ERR_INVALID, "node '%s' has a non-finite transform", name);
            l = mr_m4_from_trs(t, q, sc);
        }
        if (!mr_m4_is_finite(&l)) fail(MR_ERR_INVALID, "node '%s' has a non-finite transform", name);
        return l;
    }

    void nodes() {
        std::vector<int> roots;
        if (!m.scenes.empty()) {
            size_t si = 0;
            if (m.defaultScene >= 0 && (size_t)m.defaultScene < m.scenes.size()) si = (size_t)m.defaultScene;
            else if (m.defaultScene >= 0) warning("default scene does not exist; using scene 0");
            roots = m.scenes[si].nodes;
        } else {
            // No scenes: every node that is nobody's child is a root.
            std::vector<char> is_child(m.nodes.size(), 0);
            for (const tinygltf::Node &n : m.nodes)
                for (int c : n.children)
                    if (c >= 0 && (size_t)c < m.nodes.size()) is_child[(size_t)c] = 1;
            for (size_t i = 0; i < m.nodes.size(); i++)
                if (!is_child[i]) roots.push_back((int)i);
        }
        struct Item {
            int node;
            int32_t parent;
        };
        std::vector<char> seen(m.nodes.size(), 0);
        std::vector<Item> stack;  // explicit stack: deep hierarchies cannot overflow the C stack
        for (size_t i = roots.size(); i-- > 0;) stack.push_back(Item{roots[i], -1});
        size_t visited = 0;
        while (!stack.empty()) {
            if ((++visited & 4095) == 0) progress_nodes(visited);
            Item it = stack.back();
            stack.pop_back();
            if (it.node < 0 || (size_t)it.node >= m.nodes.size())
                fail(MR_ERR_PARSE, "node %d does not exist", it.node);
            if (seen[(size_t)it.node])
                fail(MR_ERR_INVALID, "node %d is reached twice (a cycle or a shared child)", it.node);
            seen[(size_t)it.node] = 1;
            const tinygltf::Node &gn = m.nodes[(size_t)it.node];
            mr_node n;
            std::memset(&n, 0, sizeof n);
            if (gn.name.empty()) std::snprintf(n.name, sizeof n.name, "node_%d", it.node);
            else std::snprintf(n.name, sizeof n.name, "%s", gn.name.c_str());
            mr_dmat4 local = local_matrix(gn, n.name);
            const mr_node *parent = it.parent >= 0 ? &s->nodes[it.parent] : nullptr;
            n.world = parent ? mr_m4_mul(&parent->world, &local) : local;
            if (!mr_m4_is_finite(&n.world)) fail(MR_ERR_INVALID, "node '%s' has a non-finite transform", n.name);
            n.parent = it.parent;
            bool hidden = (parent && parent->layer == MR_LAYER_HIDDEN) || extras_hidden(gn.extras);
            for (size_t k = 0; !hidden && k < globs.size(); k++) hidden = globs[k] && mr_glob_match(globs[k], n.name);
            n.layer = hidden ? MR_LAYER_HIDDEN : MR_LAYER_VISIBLE;
            n.mesh_first = -1;
            if (gn.mesh >= 0) {
                if ((size_t)gn.mesh >= m.meshes.size()) fail(MR_ERR_PARSE, "node '%s': mesh %d does not exist", n.name, gn.mesh);
                std::pair<int32_t, int32_t> r = mesh(gn.mesh);
                n.mesh_first = r.first;
                n.mesh_count = r.second;
            }
            const bool later = n.mesh_first >= 0 && n.mesh_first > s->mesh_count - n.mesh_count;  // still pending
            const int32_t first = n.mesh_first, count = n.mesh_count;
            if (later) {
                n.mesh_first = -1;
                n.mesh_count = 0;
            }
            int32_t idx = mr_scene_add_node(s, &n);
            if (idx < 0) fail(MR_ERR_NOMEM, "cannot add node '%s'", n.name);
            if (gn.extras.IsObject() || gn.name.size() == 22) {  // IFC identity (element.c)
                cJSON *ex = value_to_json(gn.extras);
                mr_scene_element_from_extras(s, idx, ex);
                cJSON_Delete(ex);
            }
            if (later) node_fix.push_back(std::array<int32_t, 3>{{idx, first, count}});
            for (size_t c = gn.children.size(); c-- > 0;) stack.push_back(Item{gn.children[c], idx});
        }
    }

    void run() {
        count_view_uses();
        mesh_map.assign(m.meshes.size(), std::make_pair(-2, 0));
        tex_map.assign(m.textures.size(), -2);
        materials();
        try {
            nodes();
            flush(true);
        } catch (const Fail &) {
            earlier_failure();
            throw;
        }
        for (const std::array<int32_t, 3> &f : node_fix) {
            s->nodes[f[0]].mesh_first = f[1];
            s->nodes[f[0]].mesh_count = f[2];
        }
        report("nodes", 1, 1);
        mr_scene_update_bounds(s); 
    }
};

bool uses_extension(const tinygltf::Model &m, const char *e) {
    for (const std::string &u : m.extensionsUsed)
        if (u == e) return true;
    for (const std::string &u : m.extensionsRequired)
        if (u == e) return true;
    return false;
}

// container: the mapped file that data lies in, if it is one (its pages are
// given back as meshes are read).
mr_scene *load_memory(const void *data, size_t size, const char *base_dir, const mr_scene_params *params,
                      const std::vector<std::string> &extra_globs, const char *label, const Mapping *container) {
    if (!data || size == 0) fail(MR_ERR_PARSE, "empty glTF data");
    if (size > k_max_file) fail(MR_ERR_UNSUPPORTED, "glTF data too large (%zu bytes, over 4 GiB)", size);
    const unsigned char *bytes = static_cast<const unsigned char *>(data);
    if (size >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF) {  // UTF-8 BOM
        bytes += 3;
        size -= 3;
    }
    bool binary = size >= 4 && std::memcmp(bytes, "glTF", 4) == 0;
    Pool pool;
    if (size >= ((size_t)4 << 20)) pool.start();  // enough bytes for tasks; ready when they come
    Source src;
    src.container = container;
    src.input_bytes = size;
    Glb glb;
    std::string json;
    if (binary) {
        glb = glb_split(bytes, size);
        json = take_buffers(glb.json, glb.json_len, &glb, base_dir, &src);
    } else {
        json = take_buffers(reinterpret_cast<const char *>(bytes), size, nullptr, base_dir, &src);
    }

    
    tinygltf::TinyGLTF gltf;
    gltf.SetImageLoader(image_loader, nullptr);
    if (!base_dir) {
        tinygltf::FsCallbacks fs = {fs_no_exists, fs_no_expand, fs_no_read, fs_no_write, nullptr};
        gltf.SetFsCallbacks(fs);
    }
    if (params && params->progress) params->progress(params->progress_user, "parse", 0.0);
    tinygltf::Model model;
    std::string terr, twarn;
    std::string dir = base_dir ? base_dir : "";
    bool ok = json.size() <= UINT_MAX &&
              gltf.LoadASCIIFromString(&model, &terr, &twarn, json.data(), (unsigned)json.size(), dir);
    if (!ok) {
        std::string msg = one_line(terr.empty() ? twarn : terr);
        fail(MR_ERR_PARSE, "invalid %s: %s", binary ? "GLB" : "glTF", msg.empty() ? "parse error" : msg.c_str());
    }
    std::string().swap(json);
    for (const std::string &e : model.extensionsRequired)
        if (!extension_ok(e)) fail(MR_ERR_UNSUPPORTED, "requires glTF extension %s (not supported)", e.c_str());
    // take_buffers saw the same array unless it could not read the JSON.
    if (src.bufs.size() != model.buffers.size()) {
        if (!src.bufs.empty()) fail(MR_ERR_PARSE, "the buffers could not be read");
        for (const tinygltf::Buffer &b : model.buffers) {
            BufRef r;
            r.data_uri = true;
            src.bufs.push_back(r);
            (void)b;
        }
    }
    for (size_t i = 0; i < src.bufs.size(); i++)
        if (src.bufs[i].data_uri) {
            src.bufs[i].p = model.buffers[i].data.data();
            src.bufs[i].n = model.buffers[i].data.size();
        }
    mr_scene *scene = mr_scene_create();
    if (!scene) throw std::bad_alloc();
    SceneGuard guard(scene);
    Loader L(model, scene, src, pool);
    L.quantized = uses_extension(model, "KHR_mesh_quantization");
    if (params) {
        L.progress = params->progress;
        L.progress_user = params->progress_user;
    }
    if (params)
        for (int i = 0; i < params->hidden_glob_count; i++)
            if (params->hidden_globs) L.globs.push_back(params->hidden_globs[i]);
    for (const std::string &g : extra_globs) L.globs.push_back(g.c_str());
    L.run();
    if (model.asset.extras.IsObject() && model.asset.extras.Has("mrcheck_source")) {
        const tinygltf::Value &k = model.asset.extras.Get("mrcheck_source");
        if (k.IsString()) std::snprintf(scene->source_key, sizeof scene->source_key, "%s", k.Get<std::string>().c_str());
    }
    if (scene->element_count > 0)
        mr_scene_hide_classes(scene, params ? params->hidden_classes : nullptr, params ? params->hidden_class_count : 0);
    std::string all = one_line(twarn + (terr.empty() ? "" : "\n" + terr) + "\n" + L.warn);
    if (!all.empty()) mr_log(MR_LOG_WARN, "%s: %s", label, all.c_str());
    return guard.release();
}

// ------------------------------------------------------- scene configs

double json_finite(const cJSON *v, const char *what, const char *path) {
    if (!cJSON_IsNumber(v) || !std::isfinite(v->valuedouble)) fail(MR_ERR_INVALID, "%s: %s must be a finite number", path, what);
    return v->valuedouble;
}

void json_vec3(const cJSON *obj, const char *key, double out[3], const char *path) {
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != 3) fail(MR_ERR_INVALID, "%s: light '%s' must be 3 numbers", path, key);
    for (int k = 0; k < 3; k++) out[k] = json_finite(cJSON_GetArrayItem(a, k), key, path);
}

mr_scene *load_path(const char *path, const mr_scene_params *params, const std::vector<std::string> &extra_globs,
                    bool allow_config);

// The size of a light for soft shadows (mr_light's comment): scene units or
// degrees, never a fixed scale; anything negative, non-finite or degenerate
// is an error, not a silent point light.
void light_size(const cJSON *l, mr_light &L, const char *path) {
    const cJSON *jk = cJSON_GetObjectItemCaseSensitive(l, "kind");
    L.kind = MR_LIGHT_SUN;
    if (jk) {
        const char *k = cJSON_IsString(jk) ? jk->valuestring : "";
        if (std::strcmp(k, "sun") == 0) L.kind = MR_LIGHT_SUN;
        else if (std::strcmp(k, "rect") == 0) L.kind = MR_LIGHT_RECT;
        else if (std::strcmp(k, "sphere") == 0) L.kind = MR_LIGHT_SPHERE;
        else fail(MR_ERR_INVALID, "%s: a light 'kind' must be \"sun\", \"rect\" or \"sphere\"", path);
    }
    const cJSON *js = cJSON_GetObjectItemCaseSensitive(l, "shadows");
    if (js && !cJSON_IsBool(js)) fail(MR_ERR_INVALID, "%s: a light's 'shadows' must be true or false", path);
    L.casts = !js || cJSON_IsTrue(js);
    if (L.kind == MR_LIGHT_SUN) {
        L.angle = MR_LIGHT_DEFAULT_SUN_ANGLE;
        const cJSON *ja = cJSON_GetObjectItemCaseSensitive(l, "angle");
        if (ja) L.angle = json_finite(ja, "a light's 'angle'", path);
        if (!(L.angle >= 0 && L.angle < 90)) fail(MR_ERR_INVALID, "%s: a sun's 'angle' must be in [0, 90) degrees", path);
        return;
    }
    json_vec3(l, "position", L.position, path);
    const cJSON *jz = cJSON_GetObjectItemCaseSensitive(l, "size");
    if (L.kind == MR_LIGHT_SPHERE) {
        L.size[0] = json_finite(jz, "a sphere light's 'size' (its radius)", path);
        if (!(L.size[0] > 0)) fail(MR_ERR_INVALID, "%s: a light size must be positive", path);
        return;
    }
    if (!cJSON_IsArray(jz) || cJSON_GetArraySize(jz) != 2)
        fail(MR_ERR_INVALID, "%s: a rect light's 'size' must be [width, height]", path);
    for (int k = 0; k < 2; k++) {
        L.size[k] = json_finite(cJSON_GetArrayItem(jz, k), "a light size", path);
        if (!(L.size[k] > 0)) fail(MR_ERR_INVALID, "%s: a light size must be positive", path);
    }
    // The width's axis: given, or any direction orthogonal to the light's.
    double u[3] = {0, 0, 0};
    const double *d = L.direction;
    if (cJSON_GetObjectItemCaseSensitive(l, "axis")) {
        json_vec3(l, "axis", u, path);
    } else {
        u[std::fabs(d[0]) < 0.9 ? 0 : 2] = 1;
    }
    double dot = u[0] * d[0] + u[1] * d[1] + u[2] * d[2];
    for (int k = 0; k < 3; k++) u[k] -= dot * d[k];
    double n = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(n > 1e-9)) fail(MR_ERR_INVALID, "%s: a rect light's 'axis' is parallel to its direction", path);
    for (int k = 0; k < 3; k++) L.axis_u[k] = u[k] / n;
}

// "demo": "planned" | "built": the procedural demo hall (with its tag
// plates), built in memory, so the shipped configs work on a fresh clone
// without the files `mrcheck demo` writes. The hall marks its pipes and
// trays hidden itself; the config's globs hide more (a node whose name or an
// ancestor's name matches).
mr_scene *demo_scene(const cJSON *d, const char *path, const std::vector<std::string> &globs) {
    bool built = cJSON_IsString(d) && std::strcmp(d->valuestring, "built") == 0;
    if (!built && !(cJSON_IsString(d) && std::strcmp(d->valuestring, "planned") == 0))
        fail(MR_ERR_INVALID, "%s: 'demo' must be \"planned\" or \"built\"", path);
    mr_demo_hall hall;
    mr_error e;
    if (!mr_demo_build_tagged(nullptr, 0, &hall, &e)) throw Fail{e.code, e.msg};
    mr_scene *s = built ? hall.built : hall.planned;
    (built ? hall.built : hall.planned) = nullptr;
    mr_demo_free(&hall);
    for (int32_t i = 0; i < s->node_count; i++) {
        mr_node &n = s->nodes[i];
        bool hide = n.parent >= 0 && n.parent < i && s->nodes[n.parent].layer == MR_LAYER_HIDDEN;
        for (const std::string &g : globs) hide = hide || mr_glob_match(g.c_str(), n.name);
        if (hide) n.layer = MR_LAYER_HIDDEN;
    }
    return s;
}

mr_scene *load_config(const cJSON *cfg, const char *path, const mr_scene_params *params,
                      std::vector<std::string> globs) {
    /* A typo ("hiden") would silently change the check: name it. */
    static const char *const known[] = {"gltf", "demo", "hidden", "lights", "receivers", "shadows", "ambient",
                                        "description", nullptr};
    static const char *const light_keys[] = {"direction", "color", "kind", "position", "shadows", "angle", "size",
                                             "axis", nullptr};
    mr_json_warn_unknown(cfg, known, path);
    const cJSON *hidden = cJSON_GetObjectItemCaseSensitive(cfg, "hidden");
    if (hidden) {
        if (!cJSON_IsArray(hidden)) fail(MR_ERR_INVALID, "%s: 'hidden' must be an array of name globs", path);
        const cJSON *h;
        cJSON_ArrayForEach(h, hidden) {
            if (!cJSON_IsString(h)) fail(MR_ERR_INVALID, "%s: 'hidden' must be an array of name globs", path);
            globs.push_back(h->valuestring);
        }
    }
    mr_light lights[MR_SCENE_MAX_LIGHTS];
    int nlights = 0;
    const cJSON *jl = cJSON_GetObjectItemCaseSensitive(cfg, "lights");
    if (jl) {
        if (!cJSON_IsArray(jl)) fail(MR_ERR_INVALID, "%s: 'lights' must be an array", path);
        if (cJSON_GetArraySize(jl) > MR_SCENE_MAX_LIGHTS)
            fail(MR_ERR_INVALID, "%s: at most %d lights", path, MR_SCENE_MAX_LIGHTS);
        const cJSON *l;
        cJSON_ArrayForEach(l, jl) {
            if (!cJSON_IsObject(l)) fail(MR_ERR_INVALID, "%s: each light must be an object", path);
            mr_json_warn_unknown(l, light_keys, path);
            mr_light &L = lights[nlights++];
            double d[3], c[3] = {1, 1, 1};
            json_vec3(l, "direction", d, path);
            double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(len > 0) || !std::isfinite(len)) fail(MR_ERR_INVALID, "%s: a light direction is zero", path);
            if (cJSON_GetObjectItemCaseSensitive(l, "color")) json_vec3(l, "color", c, path);
            for (int k = 0; k < 3; k++) {
                if (c[k] < 0 || c[k] > 1e6) fail(MR_ERR_INVALID, "%s: a light colour is out of range", path);
                L.direction[k] = d[k] / len;
                L.color[k] = (float)c[k];
            }
            light_size(l, L, path);
        }
    }
    std::vector<std::string> receivers;
    const cJSON *jr = cJSON_GetObjectItemCaseSensitive(cfg, "receivers");
    if (jr) {
        if (!cJSON_IsArray(jr)) fail(MR_ERR_INVALID, "%s: 'receivers' must be an array of name globs", path);
        const cJSON *r;
        cJSON_ArrayForEach(r, jr) {
            if (!cJSON_IsString(r)) fail(MR_ERR_INVALID, "%s: 'receivers' must be an array of name globs", path);
            receivers.push_back(r->valuestring);
        }
    }
    std::string shadow_method;
    const cJSON *jsm = cJSON_GetObjectItemCaseSensitive(cfg, "shadows");
    if (jsm) {
        if (!cJSON_IsString(jsm) || std::strlen(jsm->valuestring) >= sizeof(((mr_scene *)nullptr)->shadow_method))
            fail(MR_ERR_INVALID, "%s: 'shadows' must be a method name", path);
        shadow_method = jsm->valuestring;
    }
    double ambient = -1;
    const cJSON *ja = cJSON_GetObjectItemCaseSensitive(cfg, "ambient");
    if (ja) {
        ambient = json_finite(ja, "'ambient'", path);
        if (ambient < 0 || ambient > 1) fail(MR_ERR_INVALID, "%s: 'ambient' must be in [0,1]", path);
    }
    // "hidden_classes": IFC class globs for the hidden layer (mr_scene_params).
    std::vector<std::string> classes;
    std::vector<const char *> class_ptrs;
    mr_scene_params cp;
    std::memset(&cp, 0, sizeof cp);
    if (params) cp = *params;
    const cJSON *hc = cJSON_GetObjectItemCaseSensitive(cfg, "hidden_classes");
    if (hc) {
        if (!cJSON_IsArray(hc)) fail(MR_ERR_INVALID, "%s: 'hidden_classes' must be an array of IFC class globs", path);
        const cJSON *h;
        cJSON_ArrayForEach(h, hc) {
            if (!cJSON_IsString(h)) fail(MR_ERR_INVALID, "%s: 'hidden_classes' must be an array of IFC class globs", path);
            classes.push_back(h->valuestring);
        }
        for (const std::string &c : classes) class_ptrs.push_back(c.c_str());
        static const char *const k_none[1] = {""};
        cp.hidden_classes = class_ptrs.empty() ? k_none : class_ptrs.data();
        cp.hidden_class_count = (int)class_ptrs.size();
    }
    const cJSON *g = cJSON_GetObjectItemCaseSensitive(cfg, "gltf");
    if (!cJSON_IsString(g)) g = cJSON_GetObjectItemCaseSensitive(cfg, "ifc");  // the same: recognised by content
    mr_scene *s;
    if (cJSON_IsString(g)) {
        char dir[4096], gpath[4096];
        mr_path_dir(path, dir, sizeof dir);
        mr_path_join(dir, g->valuestring, gpath, sizeof gpath);
        s = load_path(gpath, &cp, globs, false);  // throws with the model's own message
    } else {
        s = demo_scene(cJSON_GetObjectItemCaseSensitive(cfg, "demo"), path, globs);
    }
    std::memcpy(s->lights, lights, sizeof lights);
    s->light_count = nlights;
    if (ambient >= 0) s->ambient = (float)ambient;
    std::snprintf(s->shadow_method, sizeof s->shadow_method, "%s", shadow_method.c_str());
    for (const std::string &gl : receivers) {
        bool any = false;
        for (int32_t i = 0; i < s->node_count; i++) {
            mr_node &n = s->nodes[i];
            bool hit = mr_glob_match(gl.c_str(), n.name) ||
                       (n.parent >= 0 && n.parent < i && s->nodes[n.parent].shadow_catcher);
            if (hit) n.shadow_catcher = true;
            any = any || hit;
        }
        if (!any) {
            mr_scene_destroy(&s);
            fail(MR_ERR_INVALID, "%s: the receiver glob '%s' matches no node", path, gl.c_str());
        }
    }
    return s;
}

// An IFC file: converted by IFC++ (ifc_io.cc), or read from the converted
// scene cached beside it ("<file>.mrscene.glb", valid while its asset
// extras name the IFC bytes' key). The cache keeps every node visible; the
// hidden layer (name globs, IFC classes) is applied after either.
mr_scene *load_ifc(const char *path, const void *data, size_t size, const mr_scene_params *params,
                   const std::vector<std::string> &globs) {
    uint64_t h = 1469598103934665603ull;
    const unsigned char *b = static_cast<const unsigned char *>(data);
    for (size_t i = 0; i < size; i++) h = (h ^ b[i]) * 1099511628211ull;
    char key[40];
    std::snprintf(key, sizeof key, "ifc1-%016llx-%llu", (unsigned long long)h,
                  (unsigned long long)(size % 1000000000000ull));
    const bool cached = !(params && params->no_cache);
    std::string cache = std::string(path) + ".mrscene.glb";
    mr_scene *s = nullptr;
    struct stat st;
    if (cached && ::stat(cache.c_str(), &st) == 0) {
        try {
            s = load_path(cache.c_str(), params, globs, false);
        } catch (const Fail &) {
            s = nullptr;  // a broken cache is rebuilt, never trusted
        }
        if (s && std::strcmp(s->source_key, key) != 0) mr_scene_destroy(&s);
        if (s) return s;
    }
    mr_error e;
    s = mr_ifc_load_memory(data, size, params, &e);
    if (!s) fail(e.code, "%s", e.msg);
    std::snprintf(s->source_key, sizeof s->source_key, "%s", key);
    if (cached) {
        mr_error we;
        if (!mr_scene_save_glb(s, cache.c_str(), &we))
            mr_log(MR_LOG_WARN, "%s: the converted scene is not cached: %s", path, we.msg);
    }
    std::vector<const char *> all;
    if (params && params->hidden_globs)
        for (int i = 0; i < params->hidden_glob_count; i++) all.push_back(params->hidden_globs[i]);
    for (const std::string &g : globs) all.push_back(g.c_str());
    for (int32_t i = 0; i < s->node_count; i++)
        for (const char *g : all)
            if (g && mr_glob_match(g, s->nodes[i].name)) s->nodes[i].layer = MR_LAYER_HIDDEN;
    mr_scene_hide_classes(s, params ? params->hidden_classes : nullptr, params ? params->hidden_class_count : 0);
    return s;
}

mr_scene *load_path(const char *path, const mr_scene_params *params, const std::vector<std::string> &extra_globs,
                    bool allow_config) {
    size_t size = 0;
    if (params && params->progress) params->progress(params->progress_user, "read", 0.0);
    // Mapped, not read: a big .glb's bytes are paged in as meshes are read
    // and given back after (Source::consumed), never all resident at once.
    Mapping fm;
    map_file(path, &fm);
    const void *data = fm.addr;
    size = fm.len;
    char dir[4096];
    mr_path_dir(path, dir, sizeof dir);
    mr_scene *s = nullptr;
    try {
        if (size >= 4 && std::memcmp(data, "glTF", 4) == 0) {
            s = load_memory(data, size, dir, params, extra_globs, path, &fm);
        } else if (mr_ifc_sniff(data, size)) {
            s = load_ifc(path, data, size, params, extra_globs);
        } else {
            size_t bom = size >= 3 && std::memcmp(data, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
        JsonGuard j{cJSON_ParseWithLength(static_cast<const char *>(data) + bom, size - bom)};
            if (!j.j || !cJSON_IsObject(j.j))
                fail(MR_ERR_PARSE, "%s: not a glTF file or scene config (neither GLB nor a JSON object)", path);
            const cJSON *g = cJSON_GetObjectItemCaseSensitive(j.j, "gltf");
            if (cJSON_GetObjectItemCaseSensitive(j.j, "asset")) {
                s = load_memory(data, size, dir, params, extra_globs, path, &fm);
            } else if (cJSON_IsString(g) || cJSON_IsString(cJSON_GetObjectItemCaseSensitive(j.j, "ifc")) ||
                       cJSON_GetObjectItemCaseSensitive(j.j, "demo")) {
                if (!allow_config) fail(MR_ERR_INVALID, "%s: a scene config cannot point to another scene config", path);
                s = load_config(j.j, path, params, extra_globs);
            } else {
                fail(MR_ERR_PARSE, "%s: not a glTF file or scene config", path);
            }
        }
    } catch (Fail &f) {
        // Every message names the file it is about.
        if (f.msg.find(path) == std::string::npos) f.msg = std::string(path) + ": " + f.msg;
        throw;
    }
    std::snprintf(s->source, sizeof s->source, "%s", path);
    return s;
}

// ---------------------------------------------------------------- save

struct Writer {
    tinygltf::Model m;
    std::vector<unsigned char> bin;

    int add_view(const void *data, size_t bytes, int target) {
        while (bin.size() % 4) bin.push_back(0);
        tinygltf::BufferView bv;
        bv.buffer = 0;
        bv.byteOffset = bin.size();
        bv.byteLength = bytes;
        bv.target = target;
        const unsigned char *p = static_cast<const unsigned char *>(data);
        bin.insert(bin.end(), p, p + bytes);
        m.bufferViews.push_back(bv);
        return (int)m.bufferViews.size() - 1;
    }

    int add_accessor(int view, int comp, int type, size_t count) {
        tinygltf::Accessor a;
        a.bufferView = view;
        a.componentType = comp;
        a.type = type;
        a.count = count;
        m.accessors.push_back(a);
        return (int)m.accessors.size() - 1;
    }

    static void png_write(void *ctx, void *data, int size) {
        std::vector<unsigned char> *v = static_cast<std::vector<unsigned char> *>(ctx);
        const unsigned char *p = static_cast<const unsigned char *>(data);
        v->insert(v->end(), p, p + size);
    }

    void texture(const mr_texture &t, int i) {
        const mr_image &im = t.image;
        if (!im.data || im.width <= 0 || im.height <= 0 || im.channels < 1 || im.channels > 4 || im.type != MR_PIX_U8)
            fail(MR_ERR_INVALID, "texture %d is not an 8-bit image", i);
        std::vector<unsigned char> png;
        if (!stbi_write_png_to_func(png_write, &png, im.width, im.height, im.channels, im.data,
                                    im.width * im.channels))
            fail(MR_ERR_IO, "cannot encode texture %d as PNG", i);
        tinygltf::Image gi;
        gi.mimeType = "image/png";
        gi.bufferView = add_view(png.data(), png.size(), 0);
        m.images.push_back(gi);
        tinygltf::Sampler smp;
        smp.magFilter = t.nearest ? TINYGLTF_TEXTURE_FILTER_NEAREST : TINYGLTF_TEXTURE_FILTER_LINEAR;
        smp.minFilter = t.nearest ? TINYGLTF_TEXTURE_FILTER_NEAREST : TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
        m.samplers.push_back(smp);
        tinygltf::Texture gt;
        gt.source = i;
        gt.sampler = i;
        m.textures.push_back(gt);
    }

    // One glTF mesh for meshes [first, first+count), positions relative to
    // the first mesh's origin. Returns -1 if nothing drawable.
    int mesh(const mr_scene *s, int32_t first, int32_t count) {
        const double *ref = s->meshes[first].origin;
        tinygltf::Mesh gm;
        gm.name = s->meshes[first].name;
        for (int32_t k = first; k < first + count; k++) {
            const mr_mesh &mm = s->meshes[k];
            if (!mm.positions || mm.vertex_count == 0 || mm.index_count == 0 || !mm.indices) continue;
            if (mm.index_count % 3) fail(MR_ERR_INVALID, "mesh '%s': index count not a multiple of 3", mm.name);
            size_t nv = mm.vertex_count;
            double d[3] = {mm.origin[0] - ref[0], mm.origin[1] - ref[1], mm.origin[2] - ref[2]};
            std::vector<float> pos(nv * 3);
            std::vector<double> lo(3, INFINITY), hi(3, -INFINITY);
            for (size_t v = 0; v < nv; v++)
                for (int c = 0; c < 3; c++) {
                    double x = (double)mm.positions[v * 3 + (size_t)c] + d[c];
                    if (!(std::fabs(x) <= 3.0e38))
                        fail(MR_ERR_INVALID, "mesh '%s' lies too far from the first mesh of its node", mm.name);
                    float f = (float)x;
                    pos[v * 3 + (size_t)c] = f;
                    lo[(size_t)c] = std::min(lo[(size_t)c], (double)f);
                    hi[(size_t)c] = std::max(hi[(size_t)c], (double)f);
                }
            for (uint32_t i = 0; i < mm.index_count; i++)
                if (mm.indices[i] >= mm.vertex_count) fail(MR_ERR_INVALID, "mesh '%s': index out of range", mm.name);
            tinygltf::Primitive p;
            p.mode = TINYGLTF_MODE_TRIANGLES;
            int pa = add_accessor(add_view(pos.data(), pos.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER),
                                  TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nv);
            m.accessors[(size_t)pa].minValues = lo;  // required by the spec for POSITION
            m.accessors[(size_t)pa].maxValues = hi;
            p.attributes["POSITION"] = pa;
            if (mm.normals)
                p.attributes["NORMAL"] = add_accessor(add_view(mm.normals, nv * 12, TINYGLTF_TARGET_ARRAY_BUFFER),
                                                      TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nv);
            if (mm.uvs)
                p.attributes["TEXCOORD_0"] = add_accessor(add_view(mm.uvs, nv * 8, TINYGLTF_TARGET_ARRAY_BUFFER),
                                                          TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, nv);
            p.indices = add_accessor(add_view(mm.indices, (size_t)mm.index_count * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                     TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, mm.index_count);
            p.material = mm.material >= 0 && mm.material < s->material_count ? mm.material : -1;
            gm.primitives.push_back(p);
        }
        if (gm.primitives.empty()) return -1;
        m.meshes.push_back(gm);
        return (int)m.meshes.size() - 1;
    }

    std::string run(const mr_scene *s) {
        m.asset.version = "2.0";
        m.asset.generator = "mrcheck";
        if (s->source_key[0]) {
            tinygltf::Value::Object ax;
            ax["mrcheck_source"] = tinygltf::Value(std::string(s->source_key));
            m.asset.extras = tinygltf::Value(ax);
        }
        for (int32_t i = 0; i < s->texture_count; i++) texture(s->textures[i], i);
        for (int32_t i = 0; i < s->material_count; i++) {
            const mr_material &mat = s->materials[i];
            tinygltf::Material gm;
            gm.name = std::string(mat.name, strnlen(mat.name, sizeof mat.name));
            gm.pbrMetallicRoughness.baseColorFactor.assign(mat.base_color, mat.base_color + 4);
            if (mat.base_color_texture >= 0 && mat.base_color_texture < s->texture_count)
                gm.pbrMetallicRoughness.baseColorTexture.index = mat.base_color_texture;
            gm.pbrMetallicRoughness.metallicFactor = 0.0;  // plain albedo for other viewers
            gm.doubleSided = !mat.single_sided;
            m.materials.push_back(gm);
        }
        std::map<std::pair<int32_t, int32_t>, int> mesh_of;  // instancing survives the round trip
        tinygltf::Scene scene;
        for (int32_t i = 0; i < s->node_count; i++) {
            const mr_node &n = s->nodes[i];
            tinygltf::Node gn;
            gn.name = std::string(n.name, strnlen(n.name, sizeof n.name));
            mr_dmat4 world = n.world;
            bool has_mesh = n.mesh_first >= 0 && n.mesh_count > 0 && n.mesh_first < s->mesh_count &&
                            n.mesh_count <= s->mesh_count - n.mesh_first;
            if (has_mesh) {
                std::pair<int32_t, int32_t> key(n.mesh_first, n.mesh_count);
                auto it = mesh_of.find(key);
                int mi = it != mesh_of.end() ? it->second : (mesh_of[key] = mesh(s, n.mesh_first, n.mesh_count));
                if (mi >= 0) {
                    gn.mesh = mi;
                    const double *o = s->meshes[n.mesh_first].origin;
                    mr_dmat4 t = mr_m4_translate(o[0], o[1], o[2]);
                    world = mr_m4_mul(&n.world, &t);
                }
            }
            if (!mr_m4_is_finite(&world)) fail(MR_ERR_INVALID, "node '%s' has a non-finite transform", gn.name.c_str());
            gn.matrix.resize(16);
            for (int r = 0; r < 4; r++)
                for (int c = 0; c < 4; c++) gn.matrix[(size_t)(c * 4 + r)] = world.m[r * 4 + c];
            tinygltf::Value::Object ex;
            if (n.layer == MR_LAYER_HIDDEN) ex["mrcheck_layer"] = tinygltf::Value(std::string("hidden"));
            if (cJSON *ej = mr_scene_element_extras(s, i)) {
                const cJSON *c;
                cJSON_ArrayForEach(c, ej) if (c->string) ex[c->string] = json_to_value(c);
                cJSON_Delete(ej);
            }
            if (!ex.empty()) gn.extras = tinygltf::Value(ex);
            m.nodes.push_back(gn);
            scene.nodes.push_back(i);
        }
        m.scenes.push_back(scene);
        m.defaultScene = 0;
        if (!bin.empty()) {
            while (bin.size() % 4) bin.push_back(0);
            tinygltf::Buffer b;
            b.data.swap(bin);
            m.buffers.push_back(b);
        }
        tinygltf::TinyGLTF gltf;
        std::ostringstream os;
        if (!gltf.WriteGltfSceneToStream(&m, os, false, true)) fail(MR_ERR_IO, "cannot serialise glTF");
        return os.str();
    }
};

bool report(mr_error *err, mr_err_code code, const std::string &msg) {
    return mr_fail(err, code, "%s", msg.c_str());
}

}  // namespace

// ------------------------------------------------------------- C face

mr_scene *mr_scene_load_gltf_memory(const void *data, size_t size, const char *base_dir,
                                    const mr_scene_params *params, mr_error *err) {
    try {
        return load_memory(data, size, base_dir, params, std::vector<std::string>(), "glTF", nullptr);
    } catch (const Fail &f) {
        report(err, f.code, f.msg);
    } catch (const std::bad_alloc &) {
        report(err, MR_ERR_NOMEM, "out of memory loading glTF");
    } catch (const std::exception &e) {
        report(err, MR_ERR_PARSE, std::string("glTF: ") + e.what());
    } catch (...) {
        report(err, MR_ERR_PARSE, "glTF: unknown error");
    }
    return nullptr;
}

mr_scene *mr_scene_load(const char *path, const mr_scene_params *params, mr_error *err) {
    if (!path) {
        mr_fail(err, MR_ERR_INVALID, "mr_scene_load: no path");
        return nullptr;
    }
    try {
        return load_path(path, params, std::vector<std::string>(), true);
    } catch (const Fail &f) {
        // Messages that do not already name the file get it as a prefix.
        if (f.msg.find(path) == std::string::npos) report(err, f.code, std::string(path) + ": " + f.msg);
        else report(err, f.code, f.msg);
    } catch (const std::bad_alloc &) {
        mr_fail(err, MR_ERR_NOMEM, "%s: out of memory", path);
    } catch (const std::exception &e) {
        mr_fail(err, MR_ERR_PARSE, "%s: %s", path, e.what());
    } catch (...) {
        mr_fail(err, MR_ERR_PARSE, "%s: unknown error", path);
    }
    return nullptr;
}

bool mr_scene_save_glb(const mr_scene *s, const char *path, mr_error *err) {
    if (!s || !path) return mr_fail(err, MR_ERR_INVALID, "mr_scene_save_glb: NULL argument");
    std::string out;
    try {
        Writer w;
        out = w.run(s);
    } catch (const Fail &f) {
        return report(err, f.code, std::string("saving ") + path + ": " + f.msg);
    } catch (const std::bad_alloc &) {
        return mr_fail(err, MR_ERR_NOMEM, "saving %s: out of memory", path);
    } catch (const std::exception &e) {
        return mr_fail(err, MR_ERR_IO, "saving %s: %s", path, e.what());
    } catch (...) {
        return mr_fail(err, MR_ERR_IO, "saving %s: unknown error", path);
    }
    return mr_file_write_atomic(path, out.data(), out.size(), err);
}

// Only tinygltf's parse of a .glb/.gltf in memory, nothing converted: the
// reference speed the loader is measured against (bench scene).
bool mr_gltf_parse_only(const void *data, size_t size, mr_error *err) {
    try {
        if (!data || size < 4 || size > UINT_MAX) return mr_fail(err, MR_ERR_PARSE, "no glTF data");
        tinygltf::TinyGLTF gltf;
        gltf.SetImageLoader(image_loader, nullptr);
        tinygltf::FsCallbacks fs = {fs_no_exists, fs_no_expand, fs_no_read, fs_no_write, nullptr};
        gltf.SetFsCallbacks(fs);
        tinygltf::Model model;
        std::string terr, twarn;
        const unsigned char *bytes = static_cast<const unsigned char *>(data);
        const bool binary = std::memcmp(bytes, "glTF", 4) == 0;
        // What tinygltf cannot read at all (gltfpack -c's fallback buffer,
        // draco indices) is changed as the loader changes it; the rest is
        // tinygltf's own parse, buffers copied as it copies them.
        Source src;
        bool changed = false;
        std::string json, glb2;
        if (binary) {
            Glb glb = glb_split(bytes, size);
            json = take_buffers(glb.json, glb.json_len, &glb, nullptr, &src, true, &changed);
            if (changed) {
                // The same GLB with the new JSON chunk (padded to 4 bytes)
                // and every chunk after it as it was.
                while (json.size() % 4) json += ' ';
                const size_t rest = 20 + glb.json_len, total = 20 + json.size() + (size - rest);
                if (total > UINT_MAX) return mr_fail(err, MR_ERR_PARSE, "glTF data too large");
                glb2.reserve(total);
                uint32_t h[5] = {0x46546C67u, 2, (uint32_t)total, (uint32_t)json.size(), 0x4E4F534Au};
                glb2.append(reinterpret_cast<const char *>(h), sizeof h);
                glb2 += json;
                glb2.append(reinterpret_cast<const char *>(bytes) + rest, size - rest);
                bytes = reinterpret_cast<const unsigned char *>(glb2.data());
                size = glb2.size();
            }
        } else {
            json = take_buffers(reinterpret_cast<const char *>(bytes), size, nullptr, nullptr, &src, true, &changed);
            if (changed) {
                bytes = reinterpret_cast<const unsigned char *>(json.data());
                size = json.size();
            }
        }
        bool ok = binary ? gltf.LoadBinaryFromMemory(&model, &terr, &twarn, bytes, (unsigned)size, "")
                         : gltf.LoadASCIIFromString(&model, &terr, &twarn, reinterpret_cast<const char *>(bytes),
                                                    (unsigned)size, "");
        if (!ok) return mr_fail(err, MR_ERR_PARSE, "invalid glTF: %s", one_line(terr).c_str());
        return true;
    } catch (const Fail &f) {
        return mr_fail(err, f.code, "%s", f.msg.c_str());
    } catch (const std::bad_alloc &) {
        return mr_fail(err, MR_ERR_NOMEM, "out of memory parsing glTF");
    } catch (...) {
        return mr_fail(err, MR_ERR_PARSE, "glTF parse error");
    }
}
