// gltf_io.cc — glTF 2.0 import/export and scene configs behind the C API of
// mr_scene.h. The only C++ file of lib/scene: tinygltf parses and writes the
// container; every accessor is read and bounds-checked here, because input
// files are untrusted. No C++ type or exception leaves this file.
#include "mr_scene.h"

#include <tiny_gltf.h>  // never TINYGLTF_IMPLEMENTATION: we link the shared lib

#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <exception>
#include <map>
#include <new>
#include <sstream>
#include <string>
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
    MeshGuard() { std::memset(&m, 0, sizeof m); }
    ~MeshGuard() {
        std::free(m.positions);
        std::free(m.normals);
        std::free(m.uvs);
        std::free(m.indices);
    }
    MeshGuard(const MeshGuard &) = delete;
    MeshGuard &operator=(const MeshGuard &) = delete;
};

template <typename T>
T *xmalloc(size_t n) {
    if (n == 0) n = 1;
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_alloc();
    T *p = static_cast<T *>(std::malloc(n * sizeof(T)));
    if (!p) throw std::bad_alloc();
    return p;
}

// ------------------------------------------------------------- images

const int k_max_image_side = 16384;

// Decodes PNG/JPEG/... to RGBA8 with stb_image. Bytes are trusted to be in
// bounds here (the caller checked them).
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

// A validated window onto accessor data: element i starts at base + i*stride
// and all count elements lie inside the buffer.
struct View {
    const unsigned char *base;
    size_t stride, count;
    int comp, ncomp;
    bool normalized;
};

View accessor_view(const tinygltf::Model &m, int idx, const char *what, const char *mesh) {
    if (idx < 0 || (size_t)idx >= m.accessors.size())
        fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d does not exist", mesh, what, idx);
    const tinygltf::Accessor &a = m.accessors[(size_t)idx];
    if (a.sparse.isSparse)
        fail(MR_ERR_UNSUPPORTED, "mesh '%s': %s accessor %d is sparse (not supported)", mesh, what, idx);
    if (a.bufferView < 0 || (size_t)a.bufferView >= m.bufferViews.size())
        fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d has no valid bufferView", mesh, what, idx);
    const tinygltf::BufferView &bv = m.bufferViews[(size_t)a.bufferView];
    if (bv.buffer < 0 || (size_t)bv.buffer >= m.buffers.size())
        fail(MR_ERR_PARSE, "mesh '%s': bufferView %d refers to a missing buffer", mesh, a.bufferView);
    const tinygltf::Buffer &b = m.buffers[(size_t)bv.buffer];
    int csize = component_size(a.componentType), ncomp = type_components(a.type);
    if (csize == 0 || ncomp == 0)
        fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d has an unknown component type or type", mesh, what, idx);
    size_t elem = (size_t)csize * (size_t)ncomp;
    size_t stride = bv.byteStride ? bv.byteStride : elem;
    if (stride < elem)
        fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d: byteStride %zu is smaller than an element (%zu)", mesh,
             what, idx, stride, elem);
    if (a.count == 0) fail(MR_ERR_INVALID, "mesh '%s': %s accessor %d is empty", mesh, what, idx);
    if (bv.byteOffset > b.data.size() || bv.byteLength > b.data.size() - bv.byteOffset)
        fail(MR_ERR_PARSE, "mesh '%s': bufferView %d lies outside its buffer", mesh, a.bufferView);
    // byteOffset + stride*(count-1) + elem <= byteLength, without overflow.
    if (a.byteOffset > bv.byteLength || elem > bv.byteLength - a.byteOffset ||
        (a.count - 1) > (bv.byteLength - a.byteOffset - elem) / stride)
        fail(MR_ERR_PARSE, "mesh '%s': %s accessor %d (%zu elements) runs past the end of bufferView %d", mesh,
             what, idx, a.count, a.bufferView);
    return View{b.data.data() + bv.byteOffset + a.byteOffset, stride, a.count, a.componentType, ncomp,
                a.normalized};
}

// Reads `n` float components per element (FLOAT, or normalised unsigned
// byte/short where allowed) into out[count*n].
void read_floats(const View &v, int n, bool allow_unorm, float *out) {
    for (size_t i = 0; i < v.count; i++) {
        const unsigned char *p = v.base + i * v.stride;
        for (int k = 0; k < n; k++) {
            float f;
            if (v.comp == TINYGLTF_COMPONENT_TYPE_FLOAT) {
                std::memcpy(&f, p + 4 * k, 4);
            } else if (allow_unorm && v.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
                f = (float)p[k] / 255.0f;
            } else {
                uint16_t u;
                std::memcpy(&u, p + 2 * k, 2);
                f = (float)u / 65535.0f;
            }
            out[i * (size_t)n + (size_t)k] = f;
        }
    }
}

bool is_float_vec(const View &v, int n) { return v.comp == TINYGLTF_COMPONENT_TYPE_FLOAT && v.ncomp == n; }

// -------------------------------------------------------------- loader

struct Loader {
    const tinygltf::Model &m;
    mr_scene *s;
    std::vector<const char *> globs;
    std::vector<std::pair<int32_t, int32_t>> mesh_map;  // glTF mesh -> (first, count); first -2: not yet
    std::vector<int32_t> tex_map;                        // glTF texture -> scene texture; -2: not yet
    std::string warn;

    void (*progress)(void *, const char *, double) = nullptr;
    void *progress_user = nullptr;

    Loader(const tinygltf::Model &model, mr_scene *scene) : m(model), s(scene) {}

    void report(const char *stage, size_t done, size_t total) {
        if (progress && total > 0) progress(progress_user, stage, (double)done / (double)total);
    }

    void warning(const std::string &w) { warn += w + "\n"; }

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
            const tinygltf::BufferView *bv =
                (size_t)img.bufferView < m.bufferViews.size() ? &m.bufferViews[(size_t)img.bufferView] : nullptr;
            const tinygltf::Buffer *b = bv && bv->buffer >= 0 && (size_t)bv->buffer < m.buffers.size()
                                            ? &m.buffers[(size_t)bv->buffer]
                                            : nullptr;
            if (!b || bv->byteOffset > b->data.size() || bv->byteLength > b->data.size() - bv->byteOffset)
                why = "image bufferView lies outside its buffer";
            else
                decode_image(b->data.data() + bv->byteOffset, bv->byteLength, &img, &why);
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
            if (mr_scene_add_material(s, &mat) < 0) throw std::bad_alloc();
        }
    }

    // Triangle list from a primitive's vertex order (indices or 0..n-1).
    static std::vector<uint32_t> triangulate(const std::vector<uint32_t> &idx, int mode, const char *mesh) {
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

    void primitive(const tinygltf::Primitive &p, const char *name, int prim_idx) {
        int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
        if (mode >= TINYGLTF_MODE_POINTS && mode <= TINYGLTF_MODE_LINE_STRIP) {
            warning(std::string("mesh '") + name + "' primitive " + std::to_string(prim_idx) +
                    ": points/lines skipped");
            return;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
            fail(MR_ERR_PARSE, "mesh '%s' primitive %d: unknown mode %d", name, prim_idx, mode);
        auto pos_it = p.attributes.find("POSITION");
        if (pos_it == p.attributes.end()) {
            warning(std::string("mesh '") + name + "' primitive " + std::to_string(prim_idx) +
                    " has no POSITION; skipped");
            return;
        }
        View pv = accessor_view(m, pos_it->second, "POSITION", name);
        if (!is_float_vec(pv, 3) || pv.normalized)
            fail(MR_ERR_PARSE, "mesh '%s': POSITION must be FLOAT VEC3", name);
        if (pv.count > UINT32_MAX) fail(MR_ERR_UNSUPPORTED, "mesh '%s': too many vertices", name);
        uint32_t nv = (uint32_t)pv.count;

        MeshGuard g;
        g.m.vertex_count = nv;
        g.m.positions = xmalloc<float>((size_t)nv * 3);
        read_floats(pv, 3, false, g.m.positions);
        for (size_t i = 0; i < (size_t)nv * 3; i++)
            if (!std::isfinite(g.m.positions[i])) fail(MR_ERR_INVALID, "mesh '%s' has a non-finite position", name);

        auto nrm_it = p.attributes.find("NORMAL");
        if (nrm_it != p.attributes.end()) {
            View nview = accessor_view(m, nrm_it->second, "NORMAL", name);
            if (!is_float_vec(nview, 3) || nview.count != nv) {
                warning(std::string("mesh '") + name + "': NORMAL is not FLOAT VEC3 per vertex; regenerated");
            } else {
                g.m.normals = xmalloc<float>((size_t)nv * 3);
                read_floats(nview, 3, false, g.m.normals);
                for (size_t i = 0; i < (size_t)nv * 3; i++)
                    if (!std::isfinite(g.m.normals[i])) {
                        warning(std::string("mesh '") + name + "' has non-finite normals; regenerated");
                        std::free(g.m.normals);
                        g.m.normals = nullptr;
                        break;
                    }
            }
        }
        auto uv_it = p.attributes.find("TEXCOORD_0");
        if (uv_it != p.attributes.end()) {
            View uview = accessor_view(m, uv_it->second, "TEXCOORD_0", name);
            bool ok_type = uview.ncomp == 2 && (uview.comp == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                                                (uview.normalized && (uview.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                                                      uview.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)));
            if (!ok_type || uview.count != nv) {
                warning(std::string("mesh '") + name + "': TEXCOORD_0 has an unsupported layout; ignored");
            } else {
                g.m.uvs = xmalloc<float>((size_t)nv * 2);
                read_floats(uview, 2, true, g.m.uvs);
                for (size_t i = 0; i < (size_t)nv * 2; i++)
                    if (!std::isfinite(g.m.uvs[i])) {
                        warning(std::string("mesh '") + name + "' has non-finite texture coordinates; ignored");
                        std::free(g.m.uvs);
                        g.m.uvs = nullptr;
                        break;
                    }
            }
        }

        std::vector<uint32_t> order;
        if (p.indices >= 0) {
            View iv = accessor_view(m, p.indices, "index", name);
            if (iv.ncomp != 1 || (iv.comp != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                  iv.comp != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                                  iv.comp != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
                fail(MR_ERR_PARSE, "mesh '%s': indices must be unsigned byte/short/int scalars", name);
            order.resize(iv.count);
            for (size_t i = 0; i < iv.count; i++) {
                const unsigned char *q = iv.base + i * iv.stride;
                uint32_t v;
                if (iv.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
                    v = q[0];
                } else if (iv.comp == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
                    uint16_t u;
                    std::memcpy(&u, q, 2);
                    v = u;
                } else {
                    std::memcpy(&v, q, 4);
                }
                if (v >= nv)
                    fail(MR_ERR_INVALID, "mesh '%s': index %u at position %zu is out of range (%u vertices)", name, v,
                         i, nv);
                order[i] = v;
            }
        } else {
            order.resize(nv);
            for (uint32_t i = 0; i < nv; i++) order[i] = i;
        }
        std::vector<uint32_t> tris = triangulate(order, mode, name);
        if (tris.size() > UINT32_MAX) fail(MR_ERR_UNSUPPORTED, "mesh '%s': too many indices", name);
        g.m.index_count = (uint32_t)tris.size();
        g.m.indices = xmalloc<uint32_t>(tris.size());
        if (!tris.empty()) std::memcpy(g.m.indices, tris.data(), tris.size() * sizeof(uint32_t));

        g.m.material = -1;
        if (p.material >= 0) {
            if ((size_t)p.material < m.materials.size() && p.material < s->material_count)
                g.m.material = p.material;
            else
                warning(std::string("mesh '") + name + "' uses missing material " + std::to_string(p.material));
        }
        std::snprintf(g.m.name, sizeof g.m.name, "%s", name);
        mr_error e;
        if (mr_scene_add_mesh(s, &g.m, &e) < 0) throw Fail{e.code, e.msg};
        // add_mesh NULLed the arrays it took; the guard frees nothing more.
    }

    std::pair<int32_t, int32_t> mesh(int mi) {
        if (mesh_map[(size_t)mi].first != -2) return mesh_map[(size_t)mi];
        const tinygltf::Mesh &gm = m.meshes[(size_t)mi];
        char name[64];
        if (gm.name.empty()) std::snprintf(name, sizeof name, "mesh_%d", mi);
        else std::snprintf(name, sizeof name, "%s", gm.name.c_str());
        int32_t first = s->mesh_count;
        for (size_t k = 0; k < gm.primitives.size(); k++) primitive(gm.primitives[k], name, (int)k);
        int32_t count = s->mesh_count - first;
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
            if ((++visited & 4095) == 0) report("nodes", visited, m.nodes.size());
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
            int32_t idx = mr_scene_add_node(s, &n);
            if (idx < 0) fail(MR_ERR_NOMEM, "cannot add node '%s'", n.name);
            for (size_t c = gn.children.size(); c-- > 0;) stack.push_back(Item{gn.children[c], idx});
        }
    }

    void run() {
        mesh_map.assign(m.meshes.size(), std::make_pair(-2, 0));
        tex_map.assign(m.textures.size(), -2);
        materials();
        nodes();
        report("nodes", 1, 1);
        mr_scene_update_bounds(s);
    }
};

// Required extensions that change nothing we read.
bool extension_ok(const std::string &e) {
    return e == "KHR_materials_unlit" || e == "KHR_materials_emissive_strength";
}

mr_scene *load_memory(const void *data, size_t size, const char *base_dir, const mr_scene_params *params,
                      const std::vector<std::string> &extra_globs, const char *label) {
    if (!data || size == 0) fail(MR_ERR_PARSE, "empty glTF data");
    if (size > UINT_MAX) fail(MR_ERR_NOMEM, "glTF data too large (%zu bytes)", size);
    const unsigned char *bytes = static_cast<const unsigned char *>(data);
    if (size >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF) {  // UTF-8 BOM
        bytes += 3;
        size -= 3;
    }
    bool binary = size >= 4 && std::memcmp(bytes, "glTF", 4) == 0;

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
    bool ok = binary ? gltf.LoadBinaryFromMemory(&model, &terr, &twarn, bytes, (unsigned)size, dir)
                     : gltf.LoadASCIIFromString(&model, &terr, &twarn, reinterpret_cast<const char *>(bytes),
                                                (unsigned)size, dir);
    if (!ok) {
        std::string msg = one_line(terr.empty() ? twarn : terr);
        fail(MR_ERR_PARSE, "invalid %s: %s", binary ? "GLB" : "glTF", msg.empty() ? "parse error" : msg.c_str());
    }
    for (const std::string &e : model.extensionsRequired)
        if (!extension_ok(e)) fail(MR_ERR_UNSUPPORTED, "requires glTF extension %s (not supported)", e.c_str());
    mr_scene *scene = mr_scene_create();
    if (!scene) throw std::bad_alloc();
    SceneGuard guard(scene);
    Loader L(model, scene);
    if (params) {
        L.progress = params->progress;
        L.progress_user = params->progress_user;
    }
    if (params)
        for (int i = 0; i < params->hidden_glob_count; i++)
            if (params->hidden_globs) L.globs.push_back(params->hidden_globs[i]);
    for (const std::string &g : extra_globs) L.globs.push_back(g.c_str());
    L.run();
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

struct JsonGuard {
    cJSON *j;
    ~JsonGuard() { cJSON_Delete(j); }
};

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
    const cJSON *g = cJSON_GetObjectItemCaseSensitive(cfg, "gltf");
    mr_scene *s;
    if (cJSON_IsString(g)) {
        char dir[4096], gpath[4096];
        mr_path_dir(path, dir, sizeof dir);
        mr_path_join(dir, g->valuestring, gpath, sizeof gpath);
        s = load_path(gpath, params, globs, false);  // throws with the glTF's own message
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

mr_scene *load_path(const char *path, const mr_scene_params *params, const std::vector<std::string> &extra_globs,
                    bool allow_config) {
    mr_error e;
    size_t size = 0;
    if (params && params->progress) params->progress(params->progress_user, "read", 0.0);
    void *data = mr_file_read(path, &size, (size_t)2 << 30, &e);
    if (!data) throw Fail{e.code, e.msg};
    struct Free {
        void *p;
        ~Free() { std::free(p); }
    } data_guard{data};
    if (size == 0) fail(MR_ERR_PARSE, "%s is empty", path);
    char dir[4096];
    mr_path_dir(path, dir, sizeof dir);
    mr_scene *s = nullptr;
    try {
        if (size >= 4 && std::memcmp(data, "glTF", 4) == 0) {
            s = load_memory(data, size, dir, params, extra_globs, path);
        } else {
            size_t bom = size >= 3 && std::memcmp(data, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
        JsonGuard j{cJSON_ParseWithLength(static_cast<const char *>(data) + bom, size - bom)};
            if (!j.j || !cJSON_IsObject(j.j))
                fail(MR_ERR_PARSE, "%s: not a glTF file or scene config (neither GLB nor a JSON object)", path);
            const cJSON *g = cJSON_GetObjectItemCaseSensitive(j.j, "gltf");
            if (cJSON_GetObjectItemCaseSensitive(j.j, "asset")) {
                s = load_memory(data, size, dir, params, extra_globs, path);
            } else if (cJSON_IsString(g) || cJSON_GetObjectItemCaseSensitive(j.j, "demo")) {
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
        for (int32_t i = 0; i < s->texture_count; i++) texture(s->textures[i], i);
        for (int32_t i = 0; i < s->material_count; i++) {
            const mr_material &mat = s->materials[i];
            tinygltf::Material gm;
            gm.name = std::string(mat.name, strnlen(mat.name, sizeof mat.name));
            gm.pbrMetallicRoughness.baseColorFactor.assign(mat.base_color, mat.base_color + 4);
            if (mat.base_color_texture >= 0 && mat.base_color_texture < s->texture_count)
                gm.pbrMetallicRoughness.baseColorTexture.index = mat.base_color_texture;
            gm.pbrMetallicRoughness.metallicFactor = 0.0;  // plain albedo for other viewers
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
            if (n.layer == MR_LAYER_HIDDEN) {
                tinygltf::Value::Object ex;
                ex["mrcheck_layer"] = tinygltf::Value(std::string("hidden"));
                gn.extras = tinygltf::Value(ex);
            }
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
        return load_memory(data, size, base_dir, params, std::vector<std::string>(), "glTF");
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
        bool ok = std::memcmp(bytes, "glTF", 4) == 0
                      ? gltf.LoadBinaryFromMemory(&model, &terr, &twarn, bytes, (unsigned)size, "")
                      : gltf.LoadASCIIFromString(&model, &terr, &twarn, reinterpret_cast<const char *>(bytes),
                                                 (unsigned)size, "");
        if (!ok) return mr_fail(err, MR_ERR_PARSE, "invalid glTF: %s", one_line(terr).c_str());
        return true;
    } catch (const std::bad_alloc &) {
        return mr_fail(err, MR_ERR_NOMEM, "out of memory parsing glTF");
    } catch (...) {
        return mr_fail(err, MR_ERR_PARSE, "glTF parse error");
    }
}
