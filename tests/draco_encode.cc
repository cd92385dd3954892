// draco_encode.cc — test helper for test_gltf_ext: a triangle mesh encoded
// with Debian's libdraco (the encoder the loader never needs), so the
// KHR_draco_mesh_compression path is tested on real draco data.
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include <cstdlib>
#include <cstring>

extern "C" unsigned char *test_draco_encode(const float *pos, unsigned nv, const unsigned *idx, unsigned ntri, int bits,
                                            size_t *out_n, int *pos_id);

extern "C" unsigned char *test_draco_encode(const float *pos, unsigned nv, const unsigned *idx, unsigned ntri, int bits,
                                            size_t *out_n, int *pos_id) {
    draco::Mesh mesh;
    mesh.set_num_points(nv);
    draco::GeometryAttribute ga;
    ga.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, sizeof(float) * 3, 0);
    int att = mesh.AddAttribute(ga, true, nv);
    for (unsigned i = 0; i < nv; i++) mesh.attribute(att)->SetAttributeValue(draco::AttributeValueIndex(i), pos + 3 * i);
    for (unsigned t = 0; t < ntri; t++) {
        draco::Mesh::Face f = {draco::PointIndex(idx[3 * t]), draco::PointIndex(idx[3 * t + 1]),
                               draco::PointIndex(idx[3 * t + 2])};
        mesh.AddFace(f);
    }
    *pos_id = (int)mesh.attribute(att)->unique_id();
    draco::Encoder enc;
    enc.SetAttributeQuantization(draco::GeometryAttribute::POSITION, bits);
    draco::EncoderBuffer buf;
    if (!enc.EncodeMeshToBuffer(mesh, &buf).ok()) return nullptr;
    unsigned char *out = static_cast<unsigned char *>(std::malloc(buf.size()));
    if (!out) return nullptr;
    std::memcpy(out, buf.data(), buf.size());
    *out_n = buf.size();
    return out;
}
