/* Element identity: which node is which building element (IFC GlobalId,
 * class, storey, property sets), and the hidden layer taken from classes. */
#include "mr_scene.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static bool grow(void **arr, int32_t count, int32_t *cap, size_t elem) {
    if (count < *cap) return true;
    if (*cap >= INT32_MAX / 2) return false;
    int32_t ncap = *cap ? *cap * 2 : 16;
    void *p = realloc(*arr, (size_t)ncap * elem);
    if (!p) return false;
    *arr = p;
    *cap = ncap;
    return true;
}

/* Index of the first element with node >= n. */
static int32_t lower_bound(const mr_scene *s, int32_t n) {
    int32_t lo = 0, hi = s->element_count;
    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (s->elements[mid].node < n) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

bool mr_scene_add_element(mr_scene *s, mr_element *e) {
    if (!s || !e) return false;
    if (e->node < 0 || e->node >= s->node_count ||
        !grow((void **)&s->elements, s->element_count, &s->element_cap, sizeof *s->elements)) {
        free(e->props);
        e->props = NULL;
        return false;
    }
    e->guid[sizeof e->guid - 1] = 0;
    e->ifc_class[sizeof e->ifc_class - 1] = 0;
    if (e->storey >= s->storey_count || e->storey < -1) e->storey = -1;
    int32_t at = lower_bound(s, e->node);
    if (at < s->element_count && s->elements[at].node == e->node) {
        free(s->elements[at].props);
        s->elements[at] = *e;
    } else {
        memmove(&s->elements[at + 1], &s->elements[at], (size_t)(s->element_count - at) * sizeof *s->elements);
        s->elements[at] = *e;
        s->element_count++;
    }
    e->props = NULL;
    return true;
}

int32_t mr_scene_storey(mr_scene *s, const char *name, const char *guid, double elevation) {
    if (!s) return -1;
    if (!name) name = "";
    for (int32_t i = 0; i < s->storey_count; i++)
        if (strncmp(s->storeys[i].name, name, sizeof s->storeys[i].name - 1) == 0) return i;
    if (!grow((void **)&s->storeys, s->storey_count, &s->storey_cap, sizeof *s->storeys)) return -1;
    mr_storey *st = &s->storeys[s->storey_count];
    memset(st, 0, sizeof *st);
    snprintf(st->name, sizeof st->name, "%s", name);
    snprintf(st->guid, sizeof st->guid, "%s", guid ? guid : "");
    st->elevation = elevation == elevation ? elevation : 0;
    return s->storey_count++;
}

mr_element_words mr_scene_element_words(const mr_scene *s, int32_t node) {
    mr_element_words w;
    memset(&w, 0, sizeof w);
    if (!s || node < 0 || node >= s->node_count) return w;
    const mr_element *e = mr_scene_element_of(s, node);
    int32_t named = e ? e->node : node;
    snprintf(w.name, sizeof w.name, "%s", s->nodes[named].name);
    if (e) {
        snprintf(w.guid, sizeof w.guid, "%s", e->guid);
        snprintf(w.ifc_class, sizeof w.ifc_class, "%s", e->ifc_class);
    }
    return w;
}

void mr_scene_element_describe(const mr_scene *s, int32_t node, int max_props, char *out, size_t n) {
    if (!out || n == 0) return;
    out[0] = 0;
    mr_element_words w = mr_scene_element_words(s, node);
    if (!w.name[0] && !w.guid[0]) return;
    const mr_element *e = mr_scene_element_of(s, node);
    size_t k = 0;
#define ADD(...) do { int w_ = snprintf(out + k, n - k, __VA_ARGS__); if (w_ > 0) k = k + (size_t)w_ < n ? k + (size_t)w_ : n - 1; } while (0)
    ADD("%s", w.name[0] ? w.name : w.guid);
    if (w.ifc_class[0]) ADD(" \xc2\xb7 %s", w.ifc_class);
    if (e && e->storey >= 0 && e->storey < s->storey_count) ADD(" \xc2\xb7 %s", s->storeys[e->storey].name);
    cJSON *props = e && e->props ? cJSON_Parse(e->props) : NULL;
    int shown = 0;
    const cJSON *set;
    cJSON_ArrayForEach(set, props) {
        const cJSON *v;
        cJSON_ArrayForEach(v, set) {
            if (shown >= max_props) break;
            char val[64];
            if (cJSON_IsString(v)) snprintf(val, sizeof val, "%s", v->valuestring);
            else if (cJSON_IsBool(v)) snprintf(val, sizeof val, "%s", cJSON_IsTrue(v) ? "true" : "false");
            else if (cJSON_IsNumber(v)) snprintf(val, sizeof val, "%g", v->valuedouble);
            else continue;
            ADD("%s%s=%s", shown ? ", " : " \xc2\xb7 ", v->string ? v->string : "?", val);
            shown++;
        }
    }
#undef ADD
    cJSON_Delete(props);
}

const mr_element *mr_scene_element_of(const mr_scene *s, int32_t node) {
    if (!s || s->element_count == 0) return NULL;
    for (int guard = 0; node >= 0 && node < s->node_count && guard < 4096; guard++) {
        int32_t at = lower_bound(s, node);
        if (at < s->element_count && s->elements[at].node == node) return &s->elements[at];
        int32_t p = s->nodes[node].parent;
        if (p >= node) break; /* parents come first; anything else is not a tree */
        node = p;
    }
    return NULL;
}

int32_t mr_scene_node_of_guid(const mr_scene *s, const char *guid) {
    if (!s || !guid || !guid[0]) return -1;
    for (int32_t i = 0; i < s->element_count; i++)
        if (strcmp(s->elements[i].guid, guid) == 0) return s->elements[i].node;
    return -1;
}

bool mr_ifc_guid_valid(const char *t) {
    if (!t || strlen(t) != 22 || t[0] < '0' || t[0] > '3') return false;
    for (int i = 0; i < 22; i++) {
        unsigned char c = (unsigned char)t[i];
        if (!(isalnum(c) || c == '_' || c == '$')) return false;
    }
    return true;
}

/* IfcDistributionElement and its subtypes, IFC2x3 and IFC4, lower case. */
static const char *const k_distribution[] = {
    "ifcdistributionelement", "ifcdistributionflowelement", "ifcdistributioncontrolelement",
    "ifcdistributionchamberelement", "ifcflowsegment", "ifcflowfitting", "ifcflowterminal",
    "ifcflowcontroller", "ifcflowmovingdevice", "ifcflowstoragedevice", "ifcflowtreatmentdevice",
    "ifcenergyconversiondevice", "ifcpipesegment", "ifcpipefitting", "ifcductsegment", "ifcductfitting",
    "ifccablecarriersegment", "ifccablecarrierfitting", "ifccablesegment", "ifccablefitting",
    "ifcductsilencer", "ifcairterminal", "ifcairterminalbox", "ifcvalve", "ifcdamper", "ifcpump", "ifcfan",
    "ifccompressor", "ifctank", "ifcfilter", "ifcinterceptor", "ifcflowinstrument", "ifcflowmeter",
    "ifcsensor", "ifcactuator", "ifcalarm", "ifccontroller", "ifcunitaryequipment", "ifcboiler",
    "ifcchiller", "ifccoil", "ifccoolingtower", "ifcheatexchanger", "ifchumidifier", "ifcspaceheater",
    "ifcelectricappliance", "ifcelectricdistributionboard", "ifcelectricflowstoragedevice",
    "ifcelectricgenerator", "ifcelectricmotor", "ifcelectrictimecontrol", "ifcjunctionbox", "ifcoutlet",
    "ifcswitchingdevice", "ifcprotectivedevice", "ifcprotectivedevicetrippingunit", "ifclamp",
    "ifclightfixture", "ifcsanitaryterminal", "ifcwasteterminal", "ifcfiresuppressionterminal",
    "ifcstackterminal", "ifcaudiovisualappliance", "ifccommunicationsappliance", "ifcmedicaldevice",
    "ifcburner", "ifcevaporativecooler", "ifcevaporator", "ifccondenser", "ifcengine", "ifctransformer",
    "ifcmotorconnection", "ifcsolardevice", "ifctubebundle",
    "ifcunitarycontrolelement", "ifcairtoairheatrecovery", "ifccooledbeam", "ifcdistributionport",
};

static void lower(const char *in, char *out, size_t n) {
    size_t i = 0;
    for (; in && in[i] && i + 1 < n; i++) out[i] = (char)tolower((unsigned char)in[i]);
    out[i] = 0;
}

bool mr_ifc_class_is_distribution(const char *cls) {
    char c[64];
    lower(cls, c, sizeof c);
    size_t n = strlen(c);
    if (n > 12 && strcmp(c + n - 12, "standardcase") == 0) c[n -= 12] = 0;
    if (n > 4 && strcmp(c + n - 4, "type") == 0) c[n -= 4] = 0;
    for (size_t i = 0; i < sizeof k_distribution / sizeof *k_distribution; i++)
        if (strcmp(c, k_distribution[i]) == 0) return true;
    return false;
}

void mr_scene_hide_classes(mr_scene *s, const char *const *globs, int glob_count) {
    if (!s) return;
    for (int32_t i = 0; i < s->element_count; i++) {
        const mr_element *e = &s->elements[i];
        if (!e->ifc_class[0]) continue;
        bool hide = false;
        if (!globs) {
            hide = mr_ifc_class_is_distribution(e->ifc_class);
        } else {
            char c[64], g[128];
            lower(e->ifc_class, c, sizeof c);
            for (int k = 0; k < glob_count && !hide; k++) {
                lower(globs[k], g, sizeof g);
                hide = mr_glob_match(g, c);
            }
        }
        if (hide) s->nodes[e->node].layer = MR_LAYER_HIDDEN;
    }
    for (int32_t i = 0; i < s->node_count; i++) {
        int32_t p = s->nodes[i].parent;
        if (p >= 0 && p < i && s->nodes[p].layer == MR_LAYER_HIDDEN) s->nodes[i].layer = MR_LAYER_HIDDEN;
    }
}

void mr_scene_elements_free(mr_scene *s) {
    if (!s) return;
    for (int32_t i = 0; i < s->element_count; i++) free(s->elements[i].props);
    free(s->elements);
    free(s->storeys);
    s->elements = NULL;
    s->storeys = NULL;
    s->element_count = s->element_cap = s->storey_count = s->storey_cap = 0;
}

/* ----------------------------------------------- identity in glTF extras */

static const char *str_of(const cJSON *o, const char *const *keys) {
    for (int i = 0; keys[i]; i++) {
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, keys[i]);
        if (cJSON_IsString(v) && v->valuestring[0]) return v->valuestring;
    }
    return NULL;
}

/* Keys read (first found wins). Ours, as mr_scene_save_glb writes them:
 * ifc_guid, ifc_class, ifc_storey, ifc_storey_elevation, ifc_props. Others
 * seen in IFC-to-glTF exports: GlobalId / globalId / guid / IfcGUID for the
 * GlobalId (IfcConvert writes none in extras but names each node by its
 * GlobalId, which is taken when the name has a GlobalId's shape), IfcClass /
 * ifcClass / IfcType / ifcType / ifc_type / type for the class (when it
 * starts with "Ifc"), storey / Storey / BuildingStorey / IfcBuildingStorey
 * for the storey's name. */
static const char *const k_guid_keys[] = {"ifc_guid", "GlobalId", "globalId", "guid", "IfcGUID", "ifcGuid", NULL};
static const char *const k_class_keys[] = {"ifc_class", "IfcClass", "ifcClass", "IfcType", "ifcType", "ifc_type", "type", NULL};
static const char *const k_storey_keys[] = {"ifc_storey", "storey", "Storey", "BuildingStorey", "IfcBuildingStorey", NULL};

bool mr_scene_element_from_extras(mr_scene *s, int32_t node, const cJSON *extras) {
    if (!s || node < 0 || node >= s->node_count) return false;
    const cJSON *ex = cJSON_IsObject(extras) ? extras : NULL;
    const char *guid = ex ? str_of(ex, k_guid_keys) : NULL;
    const char *cls = ex ? str_of(ex, k_class_keys) : NULL;
    if (cls && strncasecmp(cls, "ifc", 3) != 0) cls = NULL;
    if (guid && !mr_ifc_guid_valid(guid) && strlen(guid) >= 24) guid = NULL;
    if (!guid && mr_ifc_guid_valid(s->nodes[node].name)) guid = s->nodes[node].name;
    if (!guid && !cls) return false;
    mr_element e;
    memset(&e, 0, sizeof e);
    e.node = node;
    e.storey = -1;
    snprintf(e.guid, sizeof e.guid, "%.23s", guid ? guid : "");
    snprintf(e.ifc_class, sizeof e.ifc_class, "%.47s", cls ? cls : "");
    const char *st = ex ? str_of(ex, k_storey_keys) : NULL;
    if (st) {
        const cJSON *el = cJSON_GetObjectItemCaseSensitive(ex, "ifc_storey_elevation");
        e.storey = mr_scene_storey(s, st, NULL, cJSON_IsNumber(el) ? el->valuedouble : 0);
    }
    const cJSON *pr = ex ? cJSON_GetObjectItemCaseSensitive(ex, "ifc_props") : NULL;
    if (cJSON_IsObject(pr)) e.props = cJSON_PrintUnformatted(pr);
    else if (cJSON_IsString(pr)) {
        cJSON *p = cJSON_Parse(pr->valuestring);
        if (cJSON_IsObject(p)) e.props = cJSON_PrintUnformatted(p);
        cJSON_Delete(p);
    }
    return mr_scene_add_element(s, &e);
}

cJSON *mr_scene_element_extras(const mr_scene *s, int32_t node) {
    if (!s || s->element_count == 0) return NULL;
    int32_t at = lower_bound(s, node);
    if (at >= s->element_count || s->elements[at].node != node) return NULL;
    const mr_element *e = &s->elements[at];
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    if (e->guid[0]) cJSON_AddStringToObject(o, "ifc_guid", e->guid);
    if (e->ifc_class[0]) cJSON_AddStringToObject(o, "ifc_class", e->ifc_class);
    if (e->storey >= 0 && e->storey < s->storey_count) {
        cJSON_AddStringToObject(o, "ifc_storey", s->storeys[e->storey].name);
        cJSON_AddNumberToObject(o, "ifc_storey_elevation", s->storeys[e->storey].elevation);
    }
    if (e->props) {
        cJSON *p = cJSON_Parse(e->props);
        if (p) cJSON_AddItemToObject(o, "ifc_props", p);
    }
    return o;
}
