// draco_io.cc — KHR_draco_mesh_compression's decoder: Debian's libdraco,
// wrapped so that no draco type or exception leaves this file
// (draco_internal.h is its C face). Input bytes are untrusted.
#include "draco_internal.h"

#include <draco/compression/decode.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <new>

struct mr_draco {
    std::unique_ptr<draco::Mesh> mesh;
};

static void say(char *why, size_t n, const char *msg) {
    if (why && n) std::snprintf(why, n, "%s", msg);
}

extern "C" mr_draco *mr_draco_decode(const void *data, size_t size, char *why, size_t why_size) {
    try {
        if (!data || size == 0) {
            say(why, why_size, "no draco data");
            return nullptr;
        }
        draco::DecoderBuffer buf;
        buf.Init(static_cast<const char *>(data), size);
        draco::Decoder dec;
        auto res = dec.DecodeMeshFromBuffer(&buf);
        if (!res.ok()) {
            std::string m = "draco: " + res.status().error_msg_string();
            for (char &c : m)
                if (c == '\n' || c == '\r') c = ' ';
            say(why, why_size, m.c_str());
            return nullptr;
        }
        std::unique_ptr<mr_draco> d(new mr_draco);
        d->mesh = std::move(res).value();
        if (!d->mesh) {
            say(why, why_size, "draco: no mesh decoded");
            return nullptr;
        }
        // Every face corner must name an existing point: the caller indexes with them.
        const uint32_t np = d->mesh->num_points();
        for (draco::FaceIndex f(0); f < d->mesh->num_faces(); ++f)
            for (int k = 0; k < 3; k++)
                if (d->mesh->face(f)[k].value() >= np) {
                    say(why, why_size, "draco: a face refers to a missing point");
                    return nullptr;
                }
        return d.release();
    } catch (const std::bad_alloc &) {
        say(why, why_size, "draco: out of memory");
    } catch (...) {
        say(why, why_size, "draco: decode error");
    }
    return nullptr;
}

extern "C" uint32_t mr_draco_points(const mr_draco *d) { return d ? d->mesh->num_points() : 0; }
extern "C" uint32_t mr_draco_faces(const mr_draco *d) { return d ? d->mesh->num_faces() : 0; }

extern "C" void mr_draco_indices(const mr_draco *d, uint32_t *out) {
    size_t i = 0;
    for (draco::FaceIndex f(0); f < d->mesh->num_faces(); ++f)
        for (int k = 0; k < 3; k++) out[i++] = d->mesh->face(f)[k].value();
}

extern "C" bool mr_draco_attribute(const mr_draco *d, int unique_id, int ncomp, float *out, char *why,
                                   size_t why_size) {
    if (!d || unique_id < 0 || ncomp < 1 || ncomp > 4) {
        say(why, why_size, "draco: bad attribute request");
        return false;
    }
    const draco::PointAttribute *a = d->mesh->GetAttributeByUniqueId((uint32_t)unique_id);
    if (!a) {
        say(why, why_size, "draco: the attribute id does not exist in the draco data");
        return false;
    }
    if (a->num_components() < ncomp) {
        say(why, why_size, "draco: the attribute has too few components");
        return false;
    }
    const uint32_t np = d->mesh->num_points();
    for (uint32_t p = 0; p < np; p++) {
        draco::AttributeValueIndex v = a->mapped_index(draco::PointIndex(p));
        if (v.value() >= a->size() || !a->ConvertValue<float>(v, (int8_t)ncomp, out + (size_t)p * (size_t)ncomp)) {
            say(why, why_size, "draco: an attribute value cannot be read");
            return false;
        }
    }
    return true;
}

extern "C" void mr_draco_free(mr_draco *d) { delete d; }
