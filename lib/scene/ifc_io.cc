// IFC import through IFC++ (Debian's libifcplusplus, a 2019 snapshot that
// reads IFC2x3 and IFC4 files into its IFC4 classes and meshes them with
// carve). Everything IFC++ and carve stays in this file; the C face is in
// ifc_internal.h.
#include "ifc_internal.h"

#include <ifcpp/model/BuildingModel.h>
#include <ifcpp/model/UnitConverter.h>
#include <ifcpp/reader/ReaderSTEP.h>
#include <ifcpp/geometry/Carve/GeometryConverter.h>
#include <ifcpp/IFC4/include/IfcBuildingStorey.h>
#include <ifcpp/IFC4/include/IfcElement.h>
#include <ifcpp/IFC4/include/IfcGloballyUniqueId.h>
#include <ifcpp/IFC4/include/IfcLabel.h>
#include <ifcpp/IFC4/include/IfcIdentifier.h>
#include <ifcpp/IFC4/include/IfcLengthMeasure.h>
#include <ifcpp/IFC4/include/IfcOpeningElement.h>
#include <ifcpp/IFC4/include/IfcProduct.h>
#include <ifcpp/IFC4/include/IfcPropertySet.h>
#include <ifcpp/IFC4/include/IfcPropertySingleValue.h>
#include <ifcpp/IFC4/include/IfcSimpleProperty.h>
#include <ifcpp/IFC4/include/IfcProductRepresentation.h>
#include <ifcpp/IFC4/include/IfcRepresentation.h>
#include <ifcpp/IFC4/include/IfcRepresentationItem.h>
#include <ifcpp/IFC4/include/IfcRelVoidsElement.h>
#include <ifcpp/IFC4/include/IfcFeatureElementSubtraction.h>
#include <algorithm>
#include <ifcpp/IFC4/include/IfcRelAggregates.h>
#include <ifcpp/IFC4/include/IfcRelContainedInSpatialStructure.h>
#include <ifcpp/IFC4/include/IfcRelDefinesByProperties.h>
#include <ifcpp/IFC4/include/IfcSpace.h>
#include <ifcpp/IFC4/include/IfcSpatialStructureElement.h>
#include <ifcpp/IFC4/include/IfcValue.h>


#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace {

struct Fail {
    mr_err_code code;
    std::string msg;
};

std::string utf8(const std::wstring &w) {
    std::string out;
    for (wchar_t wc : w) {
        uint32_t c = (uint32_t)wc;
        if (c < 0x80) out += (char)c;
        else if (c < 0x800) {
            out += (char)(0xC0 | (c >> 6));
            out += (char)(0x80 | (c & 0x3F));
        } else if (c < 0x10000) {
            out += (char)(0xE0 | (c >> 12));
            out += (char)(0x80 | ((c >> 6) & 0x3F));
            out += (char)(0x80 | (c & 0x3F));
        } else if (c < 0x110000) {
            out += (char)(0xF0 | (c >> 18));
            out += (char)(0x80 | ((c >> 12) & 0x3F));
            out += (char)(0x80 | ((c >> 6) & 0x3F));
            out += (char)(0x80 | (c & 0x3F));
        }
    }
    return out;
}

// The header's text: from the start to the first "ENDSEC;" (at most 64 KiB).
std::string header_of(const char *p, size_t n) {
    size_t lim = n < 65536 ? n : 65536;
    std::string h(p, lim);
    size_t e = h.find("ENDSEC;");
    if (e != std::string::npos) h.resize(e);
    return h;
}

size_t skip_start(const char *p, size_t n) {
    size_t i = n >= 3 && std::memcmp(p, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
    while (i < n && (p[i] == ' ' || p[i] == '\t' || p[i] == '\r' || p[i] == '\n')) i++;
    return i;
}

// Context of one conversion: IFC++'s messages become progress and a count of
// the products it could not mesh (the first reason kept for the log).
struct Convert {
    const mr_scene_params *params = nullptr;
    int errors = 0;
    std::string first_error;
    static void on_message(void *self, shared_ptr<StatusCallback::Message> m) {
        Convert *c = static_cast<Convert *>(self);
        if (!m) return;
        if (m->m_message_type == StatusCallback::MESSAGE_TYPE_PROGRESS_VALUE) {
            if (c->params && c->params->progress && m->m_progress_value >= 0) {
                const char *stage = m->m_progress_type == "geometry" ? "convert" : "parse";
                c->params->progress(c->params->progress_user, stage, m->m_progress_value);
            }
        } else if (m->m_message_type == StatusCallback::MESSAGE_TYPE_ERROR) {
            if (c->errors++ == 0) c->first_error = utf8(m->m_message_text);
        }
    }
};

std::string guid_of(const shared_ptr<IfcRoot> &r) {
    return r && r->m_GlobalId ? utf8(r->m_GlobalId->m_value) : std::string();
}
std::string name_of(const shared_ptr<IfcRoot> &r) {
    return r && r->m_Name ? utf8(r->m_Name->m_value) : std::string();
}

// The storey an object stands in: its spatial container, or the container
// of what it is part of, up to the first IfcBuildingStorey.
shared_ptr<IfcBuildingStorey> storey_of(shared_ptr<IfcObjectDefinition> o) {
    for (int guard = 0; o && guard < 64; guard++) {
        if (auto st = dynamic_pointer_cast<IfcBuildingStorey>(o)) return st;
        shared_ptr<IfcObjectDefinition> next;
        if (auto el = dynamic_pointer_cast<IfcElement>(o)) {
            for (auto &w : el->m_ContainedInStructure_inverse) {
                shared_ptr<IfcRelContainedInSpatialStructure> rel = w.lock();
                if (rel && rel->m_RelatingStructure) {
                    next = rel->m_RelatingStructure;
                    break;
                }
            }
        }
        if (!next) {
            for (auto &w : o->m_Decomposes_inverse) {
                shared_ptr<IfcRelAggregates> rel = w.lock();
                if (rel && rel->m_RelatingObject) {
                    next = rel->m_RelatingObject;
                    break;
                }
            }
        }
        o = next;
    }
    return nullptr;
}

// A property's value as JSON: booleans, numbers (in the file's units) and
// text; anything else as IFC++ prints it.
cJSON *value_json(const shared_ptr<IfcValue> &v) {
    if (!v) return cJSON_CreateNull();
    std::string s = utf8(v->toString());
    if (s == ".T." || s == "T" || s == "true") return cJSON_CreateTrue();
    if (s == ".F." || s == "F" || s == "false") return cJSON_CreateFalse();
    char *end = nullptr;
    double d = std::strtod(s.c_str(), &end);
    if (!s.empty() && end && *end == 0 && std::isfinite(d)) return cJSON_CreateNumber(d);
    return cJSON_CreateString(s.c_str());
}

char *props_of(const shared_ptr<IfcProduct> &p) {
    cJSON *root = cJSON_CreateObject();
    if (!root) return nullptr;
    for (auto &w : p->m_IsDefinedBy_inverse) {
        shared_ptr<IfcRelDefinesByProperties> rel = w.lock();
        if (!rel) continue;
        auto ps = dynamic_pointer_cast<IfcPropertySet>(rel->m_RelatingPropertyDefinition);
        if (!ps) continue;
        std::string psn = ps->m_Name ? utf8(ps->m_Name->m_value) : std::string("Pset");
        cJSON *set = cJSON_GetObjectItemCaseSensitive(root, psn.c_str());
        if (!set) set = cJSON_AddObjectToObject(root, psn.c_str());
        if (!set) continue;
        for (auto &prop : ps->m_HasProperties) {
            auto sv = dynamic_pointer_cast<IfcPropertySingleValue>(prop);
            if (!sv || !sv->m_Name) continue;
            std::string pn = utf8(sv->m_Name->m_value);
            cJSON_DeleteItemFromObjectCaseSensitive(set, pn.c_str());
            cJSON_AddItemToObject(set, pn.c_str(), value_json(sv->m_NominalValue));
        }
    }
    char *out = nullptr;
    if (cJSON_GetArraySize(root) > 0) out = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    return out;
}

struct Triangles {
    std::vector<double> pos;  // scene frame (Y up), metres, 3 per corner
    std::vector<float> nrm;
};

// One product's triangles, per colour: IFC Z up to the scene's Y up.
void mesh_product(ProductShapeData &psd, std::map<uint32_t, Triangles> &by_colour) {
    carve::math::Matrix M = psd.getTransform();
    for (auto &rep : psd.m_vec_representations) {
        if (!rep) continue;
        // Only what the element looks like: not its axis, footprint or box.
        std::string id = utf8(rep->m_representation_identifier);
        if (id == "Axis" || id == "FootPrint" || id == "Box" || id == "Annotation" || id == "Profile" ||
            id == "Clearance" || id == "Reference" || id == "Lighting" || id == "Survey")
            continue;
        for (auto &item : rep->m_vec_item_data) {
            if (!item) continue;
            uint32_t colour = 0xFFBFBFBFu;  // default: light grey, opaque (ABGR)
            const std::vector<shared_ptr<AppearanceData>> *apps[2] = {&item->m_vec_item_appearances,
                                                                      &rep->m_vec_representation_appearances};
            bool found = false;
            for (int a = 0; a < 2 && !found; a++)
                for (auto &ap : *apps[a]) {
                    if (!ap || ap->m_apply_to_geometry_type == AppearanceData::GEOM_TYPE_CURVE ||
                        ap->m_apply_to_geometry_type == AppearanceData::GEOM_TYPE_TEXT)
                        continue;
                    auto q = [](double v) { return (uint32_t)std::lround(std::fmin(1.0, std::fmax(0.0, v)) * 255); };
                    const vec4 &c = ap->m_color_diffuse;
                    bool black = c.r() == 0 && c.g() == 0 && c.b() == 0;
                    const vec4 &cc = black ? ap->m_color_ambient : c;
                    double alpha = ap->m_transparency >= 0 && ap->m_transparency <= 1 ? ap->m_transparency : 1;
                    colour = q(cc.r()) | q(cc.g()) << 8 | q(cc.b()) << 16 | q(alpha) << 24;
                    found = true;
                    break;
                }
            std::vector<shared_ptr<carve::mesh::MeshSet<3>>> sets = item->m_meshsets;
            sets.insert(sets.end(), item->m_meshsets_open.begin(), item->m_meshsets_open.end());
            for (auto &ms : sets) {
                if (!ms) continue;
                CSG_Adapter::retriangulateMeshSet(ms);
                Triangles &t = by_colour[colour];
                for (auto *mesh : ms->meshes) {
                    for (auto *face : mesh->faces) {
                        if (!face || face->n_edges < 3) continue;
                        std::vector<carve::geom::vector<3>> v;
                        carve::mesh::Edge<3> *e = face->edge;
                        for (size_t k = 0; k < face->n_edges && e; k++, e = e->next) v.push_back(M * e->vert->v);
                        if (v.size() < 3) continue;
                        for (size_t k = 1; k + 1 < v.size(); k++) {  // a fan: faces are triangles or quads here
                            const carve::geom::vector<3> *c3[3] = {&v[0], &v[k], &v[k + 1]};
                            double ux = c3[1]->x - c3[0]->x, uy = c3[1]->y - c3[0]->y, uz = c3[1]->z - c3[0]->z;
                            double vx = c3[2]->x - c3[0]->x, vy = c3[2]->y - c3[0]->y, vz = c3[2]->z - c3[0]->z;
                            double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
                            double len = std::sqrt(nx * nx + ny * ny + nz * nz);
                            if (!(len > 0) || !std::isfinite(len)) continue;
                            for (int j = 0; j < 3; j++) {
                                t.pos.push_back(c3[j]->x);
                                t.pos.push_back(c3[j]->z);
                                t.pos.push_back(-c3[j]->y);
                                t.nrm.push_back((float)(nx / len));
                                t.nrm.push_back((float)(nz / len));
                                t.nrm.push_back((float)(-ny / len));
                            }
                        }
                    }
                }
            }
        }
    }
}

struct Builder {
    mr_scene *s = nullptr;
    std::map<uint32_t, int32_t> material_of;

    int32_t material(uint32_t abgr) {
        auto it = material_of.find(abgr);
        if (it != material_of.end()) return it->second;
        mr_material m;
        std::memset(&m, 0, sizeof m);
        std::snprintf(m.name, sizeof m.name, "ifc_%08x", abgr);
        for (int k = 0; k < 4; k++) {
            double srgb = ((abgr >> (8 * k)) & 0xFF) / 255.0;
            // IFC colours are as displayed (sRGB); the scene's factors are linear.
            m.base_color[k] = k == 3 ? (float)srgb
                                     : (float)(srgb <= 0.04045 ? srgb / 12.92 : std::pow((srgb + 0.055) / 1.055, 2.4));
        }
        m.base_color_texture = -1;
        int32_t idx = mr_scene_add_material(s, &m);
        if (idx < 0) throw Fail{MR_ERR_NOMEM, "out of memory adding a material"};
        material_of[abgr] = idx;
        return idx;
    }

    // Adds one mesh from t; -1 if it has no triangles.
    int32_t add_mesh(const Triangles &t, int32_t mat, const std::string &name) {
        size_t nv = t.pos.size() / 3;
        if (nv < 3 || nv > 0x7FFFFFFF) return -1;
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < nv; i++)
            for (int k = 0; k < 3; k++) {
                lo[k] = std::fmin(lo[k], t.pos[i * 3 + k]);
                hi[k] = std::fmax(hi[k], t.pos[i * 3 + k]);
            }
        mr_mesh m;
        std::memset(&m, 0, sizeof m);
        std::snprintf(m.name, sizeof m.name, "%s", name.c_str());
        for (int k = 0; k < 3; k++) m.origin[k] = 0.5 * (lo[k] + hi[k]);
        m.positions = (float *)std::malloc(nv * 3 * sizeof(float));
        m.normals = (float *)std::malloc(nv * 3 * sizeof(float));
        m.indices = (uint32_t *)std::malloc(nv * sizeof(uint32_t));
        if (!m.positions || !m.normals || !m.indices) {
            std::free(m.positions);
            std::free(m.normals);
            std::free(m.indices);
            throw Fail{MR_ERR_NOMEM, "out of memory meshing the model"};
        }
        for (size_t i = 0; i < nv; i++) {
            for (int k = 0; k < 3; k++) m.positions[i * 3 + k] = (float)(t.pos[i * 3 + k] - m.origin[k]);
            m.indices[i] = (uint32_t)i;
        }
        std::memcpy(m.normals, t.nrm.data(), nv * 3 * sizeof(float));
        m.vertex_count = m.index_count = (uint32_t)nv;
        m.material = mat;
        mr_error e;
        int32_t idx = mr_scene_add_mesh(s, &m, &e);
        if (idx < 0) {
            std::free(m.positions);
            std::free(m.normals);
            std::free(m.indices);
            throw Fail{e.code, e.msg};
        }
        return idx;
    }
};

mr_scene *convert(const char *data, size_t size, const mr_scene_params *params) {
    size_t at = skip_start(data, size);
    if (size - at < 13 || std::memcmp(data + at, "ISO-10303-21;", 13) != 0)
        throw Fail{MR_ERR_PARSE, "not an IFC file (no ISO-10303-21 header)"};
    if (!mr_ifc_sniff(data, size)) throw Fail{MR_ERR_PARSE, "a STEP file without an IFC schema in FILE_SCHEMA"};
    // A cut-off file reads as a smaller model: refuse it instead.
    size_t end = size;
    while (end > 0 && (data[end - 1] == ' ' || data[end - 1] == '\n' || data[end - 1] == '\r' ||
                       data[end - 1] == '\t' || data[end - 1] == 0))
        end--;
    static const char k_end[] = "END-ISO-10303-21;";
    if (end < sizeof k_end - 1 || std::memcmp(data + end - (sizeof k_end - 1), k_end, sizeof k_end - 1) != 0)
        throw Fail{MR_ERR_PARSE, "truncated IFC file (it does not end with END-ISO-10303-21;)"};

    Convert cv;
    cv.params = params;
    if (params && params->progress) params->progress(params->progress_user, "parse", 0.0);
    shared_ptr<BuildingModel> model(new BuildingModel());
    shared_ptr<ReaderSTEP> reader(new ReaderSTEP());
    reader->setMessageCallBack(&cv, &Convert::on_message);
    std::string content(data, size);
    reader->loadModelFromString(content, model);
    content.clear();
    content.shrink_to_fit();
    if (model->getMapIfcEntities().empty()) throw Fail{MR_ERR_PARSE, "no IFC entities could be read"};
    // IFC++'s geometry converter follows some references without a check:
    // a simple property's Name (GeometryConverter::readAppearanceFromPropertySet)
    // and the entries of a product's representation list and of a
    // representation's items, an opening's placement (RepresentationConverter).
    // A damaged entity leaves them empty (found by tests/fuzz/fuzz_ifc.c):
    // they are given an empty name or dropped (an opening without a
    // placement is not cut) before converting.
    for (auto &kv : model->getMapIfcEntities()) {
        if (shared_ptr<IfcSimpleProperty> sp = dynamic_pointer_cast<IfcSimpleProperty>(kv.second)) {
            if (!sp->m_Name) sp->m_Name = shared_ptr<IfcIdentifier>(new IfcIdentifier(L""));
        } else if (shared_ptr<IfcProductRepresentation> pr = dynamic_pointer_cast<IfcProductRepresentation>(kv.second)) {
            auto &v = pr->m_Representations;
            v.erase(std::remove(v.begin(), v.end(), nullptr), v.end());
        } else if (shared_ptr<IfcRepresentation> r = dynamic_pointer_cast<IfcRepresentation>(kv.second)) {
            auto &v = r->m_Items;
            v.erase(std::remove(v.begin(), v.end(), nullptr), v.end());
        } else if (shared_ptr<IfcRelVoidsElement> rv = dynamic_pointer_cast<IfcRelVoidsElement>(kv.second)) {
            if (rv->m_RelatedOpeningElement && !rv->m_RelatedOpeningElement->m_ObjectPlacement)
                rv->m_RelatedOpeningElement.reset();
        }
    }

    shared_ptr<GeometryConverter> gc(new GeometryConverter(model));
    gc->setMessageCallBack(&cv, &Convert::on_message);
    gc->convertGeometry();

    Builder b;
    b.s = mr_scene_create();
    if (!b.s) throw Fail{MR_ERR_NOMEM, "out of memory"};
    try {
        std::snprintf(b.s->source, sizeof b.s->source, "ifc");
        std::map<int, shared_ptr<ProductShapeData>> &shapes = gc->getShapeInputData();
        for (auto &kv : shapes) {
            shared_ptr<ProductShapeData> psd = kv.second;
            if (!psd || psd->m_ifc_object_definition.expired()) continue;
            shared_ptr<IfcObjectDefinition> od(psd->m_ifc_object_definition);
            auto prod = dynamic_pointer_cast<IfcProduct>(od);
            if (!prod || dynamic_pointer_cast<IfcOpeningElement>(prod) || dynamic_pointer_cast<IfcSpace>(prod)) continue;
            std::map<uint32_t, Triangles> tris;
            mesh_product(*psd, tris);
            std::string guid = guid_of(prod), name = name_of(prod);
            mr_node n;
            std::memset(&n, 0, sizeof n);
            std::snprintf(n.name, sizeof n.name, "%s", !name.empty() ? name.c_str() : guid.c_str());
            n.parent = -1;
            n.world = mr_m4_identity();
            n.mesh_first = -1;
            for (auto &ct : tris) {
                int32_t mi = b.add_mesh(ct.second, b.material(ct.first), guid);
                if (mi < 0) continue;
                if (n.mesh_first < 0) n.mesh_first = mi;
                n.mesh_count++;
            }
            if (n.mesh_first < 0) continue;  // no geometry: not a node
            int32_t node = mr_scene_add_node(b.s, &n);
            if (node < 0) throw Fail{MR_ERR_NOMEM, "cannot add a node"};
            mr_element e;
            std::memset(&e, 0, sizeof e);
            e.node = node;
            std::snprintf(e.guid, sizeof e.guid, "%s", guid.c_str());
            std::snprintf(e.ifc_class, sizeof e.ifc_class, "%s", prod->className());
            e.storey = -1;
            if (shared_ptr<IfcBuildingStorey> st = storey_of(prod)) {
                double elev = st->m_Elevation ? st->m_Elevation->m_value *
                                                    model->getUnitConverter()->getLengthInMeterFactor()
                                              : 0.0;
                std::string sn = name_of(st);
                e.storey = mr_scene_storey(b.s, sn.empty() ? guid_of(st).c_str() : sn.c_str(), guid_of(st).c_str(), elev);
            }
            e.props = props_of(prod);
            if (!mr_scene_add_element(b.s, &e)) throw Fail{MR_ERR_NOMEM, "cannot add an element"};
        }
        if (b.s->node_count == 0) {
            std::string why = cv.errors ? " (" + cv.first_error + ")" : std::string();
            throw Fail{MR_ERR_INVALID, "no IFC product with geometry" + why};
        }
        if (cv.errors)
            mr_log(MR_LOG_WARN, "IFC: %d product(s) could not be meshed fully; first: %.200s", cv.errors,
                   cv.first_error.c_str());
        mr_scene_update_bounds(b.s);
        if (params && params->progress) params->progress(params->progress_user, "convert", 1.0);
    } catch (...) {
        mr_scene_destroy(&b.s);
        throw;
    }
    return b.s;
}

}  // namespace

extern "C" bool mr_ifc_sniff(const void *vp, size_t size) {
    const char *p = static_cast<const char *>(vp);
    if (!p) return false;
    size_t at = skip_start(p, size);
    if (size - at < 13 || std::memcmp(p + at, "ISO-10303-21;", 13) != 0) return false;
    std::string h = header_of(p + at, size - at);
    size_t fs = h.find("FILE_SCHEMA");
    if (fs == std::string::npos) return false;
    size_t q = h.find('\'', fs);
    return q != std::string::npos && q + 4 <= h.size() && (h.compare(q + 1, 3, "IFC") == 0 || h.compare(q + 1, 3, "ifc") == 0);
}

extern "C" mr_scene *mr_ifc_load_memory(const void *data, size_t size, const mr_scene_params *params, mr_error *err) {
    if (!data) {
        mr_fail(err, MR_ERR_INVALID, "IFC: no data");
        return nullptr;
    }
    try {
        return convert(static_cast<const char *>(data), size, params);
    } catch (const Fail &f) {
        mr_fail(err, f.code, "%s", f.msg.c_str());
    } catch (const OutOfMemoryException &) {
        mr_fail(err, MR_ERR_NOMEM, "IFC: out of memory");
    } catch (const std::bad_alloc &) {
        mr_fail(err, MR_ERR_NOMEM, "IFC: out of memory");
    } catch (const BuildingException &e) {
        mr_fail(err, MR_ERR_PARSE, "IFC: %s", e.what());
    } catch (const carve::exception &e) {
        mr_fail(err, MR_ERR_PARSE, "IFC geometry: %s", e.str().c_str());
    } catch (const std::exception &e) {
        mr_fail(err, MR_ERR_PARSE, "IFC: %s", e.what());
    } catch (...) {
        mr_fail(err, MR_ERR_PARSE, "IFC: unknown error");
    }
    return nullptr;
}
