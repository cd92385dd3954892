/* IFC import (lib/scene/ifc_io.cc through IFC++): generated files with an
 * extruded wall with an opening, a beam and a pipe segment in a storey, in
 * millimetres and in metres at a 1e7 site offset; identity, storeys,
 * bounds, the hidden layer from classes, the cache beside the file, and a
 * truncated file refused with one line. */
#include "mr_scene.h"
#include "mr_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* s: metres per file unit (1 or 0.001); the site sits at (1e7, 2e7, 0) m. */
static void write_ifc(const char *path, double unit, bool truncate) {
    double k = 1.0 / unit; /* file units per metre */
    FILE *f = fopen(path, "w");
    if (!f) return;
    fprintf(f, "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('ViewDefinition [CoordinationView]'),'2;1');\n"
               "FILE_NAME('t.ifc','2026-01-01T00:00:00',(''),(''),'mrcheck test','mrcheck test','');\n"
               "FILE_SCHEMA(('IFC4'));\nENDSEC;\nDATA;\n");
    fprintf(f, "#1=IFCPROJECT('0YvctVUKr0kugbFTf53O9L',$,'P',$,$,$,$,(#20),#10);\n");
    fprintf(f, "#10=IFCUNITASSIGNMENT((#11));\n");
    if (unit == 1) fprintf(f, "#11=IFCSIUNIT(*,.LENGTHUNIT.,$,.METRE.);\n");
    else fprintf(f, "#11=IFCSIUNIT(*,.LENGTHUNIT.,.MILLI.,.METRE.);\n");
    fprintf(f, "#12=IFCCARTESIANPOINT((0.,0.,0.));\n#13=IFCAXIS2PLACEMENT3D(#12,$,$);\n"
               "#20=IFCGEOMETRICREPRESENTATIONCONTEXT($,'Model',3,1.E-05,#13,$);\n"
               "#21=IFCGEOMETRICREPRESENTATIONSUBCONTEXT('Body','Model',*,*,*,*,#20,$,.MODEL_VIEW.,$);\n");
    fprintf(f, "#30=IFCCARTESIANPOINT((%.3f,%.3f,0.));\n#31=IFCAXIS2PLACEMENT3D(#30,$,$);\n#32=IFCLOCALPLACEMENT($,#31);\n",
            1e7 * k, 2e7 * k);
    fprintf(f, "#33=IFCSITE('1cwlDi_hLEvPsClAelBNnz',$,'Site',$,$,#32,$,$,.ELEMENT.,$,$,$,$,$);\n");
    fprintf(f, "#34=IFCLOCALPLACEMENT(#32,#13);\n#35=IFCBUILDING('2FCZDorxHDT8NI01kdXi8P',$,'B',$,$,#34,$,$,.ELEMENT.,$,$,$);\n");
    fprintf(f, "#36=IFCCARTESIANPOINT((0.,0.,%.3f));\n#37=IFCAXIS2PLACEMENT3D(#36,$,$);\n#38=IFCLOCALPLACEMENT(#34,#37);\n", 3.0 * k);
    fprintf(f, "#39=IFCBUILDINGSTOREY('0w984V0GL6yR4z75YWgVfX',$,'Level 1',$,$,#38,$,$,.ELEMENT.,%.3f);\n", 3.0 * k);
    fprintf(f, "#40=IFCRELAGGREGATES('2YBqaV_8L15eWJ9DA1sGmT',$,$,$,#1,(#33));\n"
               "#41=IFCRELAGGREGATES('3YBqaV_8L15eWJ9DA1sGmT',$,$,$,#33,(#35));\n"
               "#42=IFCRELAGGREGATES('1YBqaV_8L15eWJ9DA1sGmT',$,$,$,#35,(#39));\n");
    /* an extruded box: profile w x d centred at (cx, cy), height h, at placement pl */
#define BOX(id, w, d, h, cx, cy)                                                                              \
    fprintf(f, "#%d=IFCCARTESIANPOINT((%.3f,%.3f));\n#%d=IFCAXIS2PLACEMENT2D(#%d,$);\n"                        \
               "#%d=IFCRECTANGLEPROFILEDEF(.AREA.,$,#%d,%.3f,%.3f);\n#%d=IFCDIRECTION((0.,0.,1.));\n"           \
               "#%d=IFCEXTRUDEDAREASOLID(#%d,#13,#%d,%.3f);\n#%d=IFCSHAPEREPRESENTATION(#21,'Body','SweptSolid',(#%d));\n" \
               "#%d=IFCPRODUCTDEFINITIONSHAPE($,$,(#%d));\n",                                                   \
            id, (cx) * k, (cy) * k, id + 1, id, id + 2, id + 1, (w) * k, (d) * k, id + 3, id + 4, id + 2, id + 3,    \
            (h) * k, id + 5, id + 4, id + 6, id + 5)
    BOX(100, 4.0, 0.2, 2.5, 2.0, 0.1); /* wall 4 x 0.2 x 2.5 m from (0,0) */
    fprintf(f, "#110=IFCWALL('3cKYIHmn9FAgfuNu$zAIQL',$,'Wall A',$,$,#38,#106,$,$);\n");
    BOX(120, 1.0, 0.4, 2.0, 2.0, 0.1); /* a door-sized opening through it */
    fprintf(f, "#130=IFCOPENINGELEMENT('0mUZjl5evF4fv8iY8r1YXS',$,'Opening',$,$,#38,#126,$,.OPENING.);\n"
               "#131=IFCRELVOIDSELEMENT('2X_CjjM6H1DAAmZ8CDKzo_',$,$,$,#110,#130);\n");
    BOX(140, 3.0, 0.3, 0.4, 1.5, 2.0); /* beam 3 x 0.3 x 0.4 */
    fprintf(f, "#150=IFCBEAM('1Bg6FSoNzDMwh2dHDeO2B3',$,'Beam B',$,$,#38,#146,$,$);\n");
    BOX(160, 0.2, 0.2, 1.0, 3.0, 3.0); /* pipe 0.2 x 0.2 x 1 */
    fprintf(f, "#170=IFCPIPESEGMENT('2pDrphlTb7b9aZcTL0Gbig',$,'Pipe C',$,$,#38,#166,$,.RIGIDSEGMENT.);\n");
    fprintf(f, "#180=IFCRELCONTAINEDINSPATIALSTRUCTURE('3vtoU2OUT8JfLLZSpkM4RI',$,$,$,(#110,#150,#170),#39);\n");
    fprintf(f, "#181=IFCPROPERTYSINGLEVALUE('IsExternal',$,IFCBOOLEAN(.T.),$);\n"
               "#182=IFCPROPERTYSET('2t$kEyDIPF0fumVijI4fMX',$,'Pset_WallCommon',$,(#181));\n"
               "#183=IFCRELDEFINESBYPROPERTIES('1AUpuQO99DN88KVElfbCPB',$,$,$,(#110),#182);\n");
    if (!truncate) fprintf(f, "ENDSEC;\nEND-ISO-10303-21;\n");
    fclose(f);
}

static const mr_element *by_guid(const mr_scene *s, const char *g) {
    int32_t n = mr_scene_node_of_guid(s, g);
    return n >= 0 ? mr_scene_element_of(s, n) : NULL;
}

int main(void) {
    char dir[1024];
    if (!mr_test_fresh_dir("test_ifc", dir, sizeof dir)) return 1;
    char pm[1200], pmm[1200], pt[1200];
    snprintf(pm, sizeof pm, "%s/m.ifc", dir);
    snprintf(pmm, sizeof pmm, "%s/mm.ifc", dir);
    snprintf(pt, sizeof pt, "%s/cut.ifc", dir);
    write_ifc(pm, 1.0, false);
    write_ifc(pmm, 0.001, false);
    write_ifc(pt, 1.0, true);

    mr_scene *sc[2] = {NULL, NULL};
    const char *paths[2] = {pm, pmm};
    for (int i = 0; i < 2; i++) {
        mr_error err;
        sc[i] = mr_scene_load(paths[i], NULL, &err);
        CHECK_MSG(sc[i] != NULL, "%s: %s", paths[i], err.msg);
        if (!sc[i]) return mr_test_finish("test_ifc");
        mr_scene *s = sc[i];
        CHECK(s->node_count == 3);      /* wall, beam, pipe; not the opening */
        CHECK(s->element_count == 3);
        CHECK(s->storey_count == 1 && strcmp(s->storeys[0].name, "Level 1") == 0);
        CHECK_NEAR(s->storeys[0].elevation, 3.0, 1e-9);
        const mr_element *w = by_guid(s, "3cKYIHmn9FAgfuNu$zAIQL");
        const mr_element *b = by_guid(s, "1Bg6FSoNzDMwh2dHDeO2B3");
        const mr_element *p = by_guid(s, "2pDrphlTb7b9aZcTL0Gbig");
        CHECK(w && b && p);
        if (!w || !b || !p) return mr_test_finish("test_ifc");
        CHECK(strcmp(w->ifc_class, "IfcWall") == 0 && strcmp(b->ifc_class, "IfcBeam") == 0 &&
              strcmp(p->ifc_class, "IfcPipeSegment") == 0);
        CHECK(w->storey == 0 && b->storey == 0 && p->storey == 0);
        CHECK(strcmp(s->nodes[w->node].name, "Wall A") == 0);
        CHECK(w->props && strstr(w->props, "\"Pset_WallCommon\":{\"IsExternal\":true}"));
        /* The view's tap says what the element is. */
        char what[300];
        mr_scene_element_describe(s, w->node, 3, what, sizeof what);
        CHECK_MSG(strcmp(what, "Wall A \xc2\xb7 IfcWall \xc2\xb7 Level 1 \xc2\xb7 IsExternal=true") == 0, "%s", what);
        mr_element_words ew = mr_scene_element_words(s, w->node);
        CHECK(strcmp(ew.guid, "3cKYIHmn9FAgfuNu$zAIQL") == 0 && strcmp(ew.ifc_class, "IfcWall") == 0 &&
              strcmp(ew.name, "Wall A") == 0);
        /* The pipe is a distribution element: the hidden layer by default. */
        CHECK(s->nodes[p->node].layer == MR_LAYER_HIDDEN);
        CHECK(s->nodes[w->node].layer == MR_LAYER_VISIBLE && s->nodes[b->node].layer == MR_LAYER_VISIBLE);
        /* Bounds in the scene's Y-up metres: x = 1e7 + 0..4, y (IFC z) = storey 3 + 0..2.5, z = -(2e7 + 0..0.2). */
        double lo[3], hi[3];
        CHECK(mr_scene_node_bounds(s, w->node, lo, hi));
        CHECK_NEAR(lo[0], 1e7, 1e-6);
        CHECK_NEAR(hi[0], 1e7 + 4, 1e-6);
        CHECK_NEAR(lo[1], 3.0, 1e-6);
        CHECK_NEAR(hi[1], 5.5, 1e-6);
        CHECK_NEAR(lo[2], -(2e7 + 0.2), 1e-5);
        CHECK_NEAR(hi[2], -2e7, 1e-5);
        /* The opening is cut: more than a box's 12 triangles. */
        CHECK(mr_scene_triangle_count(s) > 36);
    }
    /* Millimetres and metres: the same geometry. */
    CHECK(mr_scene_triangle_count(sc[0]) == mr_scene_triangle_count(sc[1]));
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(sc[0]->bounds_min[k], sc[1]->bounds_min[k], 1e-6);
        CHECK_NEAR(sc[0]->bounds_max[k], sc[1]->bounds_max[k], 1e-6);
    }
    /* The converted scene was cached beside the file, and the cache gives
     * the same scene with its identity. */
    char cache[1300];
    snprintf(cache, sizeof cache, "%s.mrscene.glb", pm);
    CHECK(access(cache, F_OK) == 0);
    mr_error err;
    mr_scene *again = mr_scene_load(pm, NULL, &err);
    CHECK(again != NULL);
    if (again) {
        CHECK(again->node_count == 3 && again->element_count == 3 && again->storey_count == 1);
        const mr_element *p = by_guid(again, "2pDrphlTb7b9aZcTL0Gbig");
        CHECK(p && strcmp(p->ifc_class, "IfcPipeSegment") == 0 && again->nodes[p->node].layer == MR_LAYER_HIDDEN);
        CHECK(mr_scene_triangle_count(again) == mr_scene_triangle_count(sc[0]));
        for (int k = 0; k < 3; k++) CHECK_NEAR(again->bounds_min[k], sc[0]->bounds_min[k], 1e-6);
        mr_scene_destroy(&again);
    }
    /* Classes configured: nothing hidden by class. */
    static const char *const none[1] = {""};
    mr_scene_params sp = MR_SCENE_DEFAULTS;
    sp.hidden_classes = none;
    sp.hidden_class_count = 0;
    mr_scene *shown = mr_scene_load(pm, &sp, &err);
    CHECK(shown != NULL);
    if (shown) {
        for (int32_t i = 0; i < shown->node_count; i++) CHECK(shown->nodes[i].layer == MR_LAYER_VISIBLE);
        mr_scene_destroy(&shown);
    }
    /* A truncated file: one line, no scene. */
    mr_scene *bad = mr_scene_load(pt, NULL, &err);
    CHECK(bad == NULL);
    CHECK(strstr(err.msg, "truncated") != NULL && strchr(err.msg, '\n') == NULL);
    mr_scene_destroy(&bad);
    mr_scene_destroy(&sc[0]);
    mr_scene_destroy(&sc[1]);
    return mr_test_finish("test_ifc");
}
