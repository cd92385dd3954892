/* The LOD hierarchy's proxies on the GPU (see mr_scene.h, "hlod.c"): one
 * vertex buffer (position + normal, as the geometry's untextured pool) and
 * one index buffer hold every proxy; a frame cuts the tree
 * (mr_hlod_cut), draws the proxies of the cut, one indirect command per
 * run of triangles of one source (scene node, mesh) with that node's id,
 * layer and mesh colour as its instance (so picking and colours see the
 * real parts), and hands the scene nodes the cut reached to the part
 * levels. Proxies are drawn with both faces (they merge parts of any
 * material). */
#include "geo_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct mr_hlod_gpu {
    const mr_hlod *h;
    GLuint vao, vbo, ibo, inst_buf, cmd_buf;
    uint32_t inst_cap;         /* records the instance buffer holds */
    int32_t *base_vertex;      /* per tree node */
    uint32_t *first_index;
    int32_t *proxies;          /* cut scratch (h->node_count) */
    gpu_instance *inst;
    draw_cmd *cmds;
    size_t cap;                /* of inst and cmds */
    float (*color)[4];         /* per scene mesh */
};

void mr_hlod_gpu_free(mr_renderer *r) {
    struct mr_hlod_gpu *hg = r->hlod;
    if (!hg) return;
    glDeleteVertexArrays(1, &hg->vao);
    glDeleteBuffers(1, &hg->vbo);
    glDeleteBuffers(1, &hg->ibo);
    glDeleteBuffers(1, &hg->inst_buf);
    glDeleteBuffers(1, &hg->cmd_buf);
    free(hg->base_vertex);
    free(hg->first_index);
    free(hg->proxies);
    free(hg->inst);
    free(hg->cmds);
    free(hg->color);
    free(hg);
    r->hlod = NULL;
}

bool mr_hlod_active(const mr_renderer *r) {
    const mr_draw_params *dp = &r->draw;
    return r->hlod && !dp->no_hlod && !dp->no_lod && dp->lod_tolerance >= 0;
}

bool mr_renderer_set_hlod(mr_renderer *r, const mr_hlod *h, mr_error *err) {
    if (!r) return mr_fail(err, MR_ERR_INVALID, "no renderer");
    mr_hlod_gpu_free(r);
    if (!h) return true;
    const mr_scene *s = r->scene;
    if (!s || !r->geo) return mr_fail(err, MR_ERR_INVALID, "set a scene before its LOD hierarchy");
    if (h->scene_node_count != s->node_count || h->scene_mesh_count != s->mesh_count ||
        h->scene_hash != mr_lod_scene_hash(s))
        return mr_fail(err, MR_ERR_INVALID, "the LOD hierarchy was built for another scene");
    struct mr_hlod_gpu *hg = calloc(1, sizeof *hg);
    if (!hg) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    r->hlod = hg;
    hg->h = h;
    size_t nn = (size_t)h->node_count;
    hg->base_vertex = calloc(nn + 1, sizeof *hg->base_vertex);
    hg->first_index = calloc(nn + 1, sizeof *hg->first_index);
    hg->proxies = malloc((nn + 1) * sizeof *hg->proxies);
    hg->color = calloc((size_t)s->mesh_count + 1, sizeof *hg->color);
    if (!hg->base_vertex || !hg->first_index || !hg->proxies || !hg->color) {
        mr_hlod_gpu_free(r);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (int32_t i = 0; i < s->mesh_count; i++) {
        const mr_mesh *m = &s->meshes[i];
        const mr_material *mat = m->material >= 0 && m->material < s->material_count ? &s->materials[m->material] : NULL;
        static const float grey[4] = {0.7f, 0.7f, 0.7f, 1.0f};
        memcpy(hg->color[i], mat ? mat->base_color : grey, sizeof hg->color[i]);
    }
    uint64_t verts = 0, idx = 0;
    for (size_t i = 0; i < nn; i++) {
        hg->base_vertex[i] = (int32_t)verts;
        hg->first_index[i] = (uint32_t)idx;
        verts += h->nodes[i].vertex_count;
        idx += h->nodes[i].index_count;
    }
    if (verts > INT32_MAX || idx > UINT32_MAX / 4) {
        mr_hlod_gpu_free(r);
        return mr_fail(err, MR_ERR_NOMEM, "LOD hierarchy too large for one upload");
    }
    glCreateVertexArrays(1, &hg->vao);
    glCreateBuffers(1, &hg->vbo);
    glCreateBuffers(1, &hg->ibo);
    glCreateBuffers(1, &hg->inst_buf);
    glCreateBuffers(1, &hg->cmd_buf);
    glNamedBufferStorage(hg->vbo, (GLsizeiptr)(verts ? verts : 1) * 24, NULL, GL_DYNAMIC_STORAGE_BIT);
    glNamedBufferStorage(hg->ibo, (GLsizeiptr)(idx ? idx : 1) * 4, NULL, GL_DYNAMIC_STORAGE_BIT);
    float *tmp = NULL;
    size_t tmp_cap = 0;
    for (size_t i = 0; i < nn; i++) {
        const mr_hlod_node *n = &h->nodes[i];
        if (n->vertex_count == 0) continue;
        if ((size_t)n->vertex_count * 6 > tmp_cap) {
            free(tmp);
            tmp_cap = (size_t)n->vertex_count * 6;
            tmp = malloc(tmp_cap * sizeof *tmp);
            if (!tmp) {
                mr_hlod_gpu_free(r);
                return mr_fail(err, MR_ERR_NOMEM, "out of memory");
            }
        }
        for (uint32_t v = 0; v < n->vertex_count; v++) {
            memcpy(tmp + 6 * (size_t)v, n->positions + 3 * (size_t)v, 12);
            memcpy(tmp + 6 * (size_t)v + 3, n->normals + 3 * (size_t)v, 12);
        }
        glNamedBufferSubData(hg->vbo, (GLintptr)hg->base_vertex[i] * 24, (GLsizeiptr)n->vertex_count * 24, tmp);
        glNamedBufferSubData(hg->ibo, (GLintptr)hg->first_index[i] * 4, (GLsizeiptr)n->index_count * 4, n->indices);
    }
    free(tmp);
    glVertexArrayVertexBuffer(hg->vao, 0, hg->vbo, 0, 24);
    glEnableVertexArrayAttrib(hg->vao, MR_ATTR_POSITION);
    glVertexArrayAttribFormat(hg->vao, MR_ATTR_POSITION, 3, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(hg->vao, MR_ATTR_POSITION, 0);
    glEnableVertexArrayAttrib(hg->vao, MR_ATTR_NORMAL);
    glVertexArrayAttribFormat(hg->vao, MR_ATTR_NORMAL, 3, GL_FLOAT, GL_FALSE, 12);
    glVertexArrayAttribBinding(hg->vao, MR_ATTR_NORMAL, 0);
    mr_geo_vao_instances(hg->vao);
    glVertexArrayElementBuffer(hg->vao, hg->ibo);
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) {
        mr_hlod_gpu_free(r);
        return mr_fail(err, MR_ERR_GL, "GL error 0x%x while uploading the LOD hierarchy", e);
    }
    return true;
}

int32_t mr_hlod_draw(mr_renderer *r, const mr_geo_view *vw, const mr_frustum *frustum, int32_t *nodes,
                     mr_frame_result *out) {
    struct mr_hlod_gpu *hg = r->hlod;
    const mr_hlod *h = hg->h;
    const mr_scene *s = r->scene;
    const mr_draw_params *dp = &r->draw;
    double t0 = mr_time_now();
    mr_hlod_cut_params cp;
    memset(&cp, 0, sizeof cp);
    cp.cam_from_world = vw->cam_from_world;
    cp.near_plane = vw->near_plane;
    cp.fmax = mr_lod_fmax(&vw->cam);
    cp.pixels = dp->lod_pixels == 0 ? MR_DRAW_DEFAULT_LOD_PIXELS : dp->lod_pixels;
    cp.tolerance = dp->lod_tolerance == 0 ? INFINITY : dp->lod_tolerance;
    cp.frustum = frustum;
    cp.layers = vw->layers;
    int32_t np = 0, nn = 0;
    if (!mr_hlod_cut(h, &cp, hg->proxies, &np, nodes, &nn)) return 0;
    size_t runs = 0;
    for (int32_t i = 0; i < np; i++) runs += h->nodes[hg->proxies[i]].run_count;
    if (runs > hg->cap) {
        gpu_instance *gi = realloc(hg->inst, runs * sizeof *gi);
        if (gi) hg->inst = gi;
        draw_cmd *dc = gi ? realloc(hg->cmds, runs * sizeof *dc) : NULL;
        if (dc) hg->cmds = dc;
        if (!gi || !dc) return nn; /* no room: the proxies are not drawn this time */
        hg->cap = runs;
    }
    uint32_t n = 0;
    uint64_t tris = 0;
    for (int32_t i = 0; i < np; i++) {
        int32_t id = hg->proxies[i];
        const mr_hlod_node *hn = &h->nodes[id];
        if (hn->run_count == 0) continue;
        mr_dmat4 T = mr_m4_translate(hn->center[0], hn->center[1], hn->center[2]);
        mr_dmat4 mv = mr_m4_mul(&vw->cam_from_world, &T);
        gpu_instance base;
        if (!mr_geo_instance_matrices(&mv, &base)) continue;
        for (uint32_t k = 0; k < hn->run_count; k++) {
            const mr_hlod_run *q = &hn->runs[k];
            gpu_instance *gi = &hg->inst[n];
            *gi = base;
            memcpy(gi->color, hg->color[q->mesh], sizeof gi->color);
            gi->ids[0] = (uint32_t)q->node + 1;
            gi->ids[1] = s->nodes[q->node].layer;
            gi->ids[2] = 0;
            gi->ids[3] = 0;
            hg->cmds[n] = (draw_cmd){q->count, 1, hg->first_index[id] + q->first, hg->base_vertex[id], n};
            n++;
            tris += q->count / 3;
        }
    }
    r->stats.cull_ms += (mr_time_now() - t0) * 1e3;
    r->stats.hlod_proxies += (uint32_t)np;
    r->stats.hlod_triangles += tris;
    r->stats.triangles += tris;
    r->stats.commands += n;
    if (n == 0) return nn;
    if (n > hg->inst_cap) {
        uint32_t c = hg->inst_cap ? hg->inst_cap : 256;
        while (c < n) c *= 2;
        glNamedBufferData(hg->inst_buf, (GLsizeiptr)c * (GLsizeiptr)sizeof(gpu_instance), NULL, GL_STREAM_DRAW);
        glVertexArrayVertexBuffer(hg->vao, 1, hg->inst_buf, 0, sizeof(gpu_instance));
        hg->inst_cap = c;
    }
    glNamedBufferSubData(hg->inst_buf, 0, (GLsizeiptr)n * (GLsizeiptr)sizeof(gpu_instance), hg->inst);
    glNamedBufferData(hg->cmd_buf, (GLsizeiptr)n * (GLsizeiptr)sizeof(draw_cmd), hg->cmds, GL_STREAM_DRAW);
    glUseProgram(vw->program);
    float proj[16];
    mr_gl_projection(&vw->cam, vw->near_plane, proj);
    glUniformMatrix4fv(MR_LOC_PROJECTION, 1, GL_FALSE, proj);
    glBindVertexArray(hg->vao);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, hg->cmd_buf);
    GLboolean culling = glIsEnabled(GL_CULL_FACE);
    if (culling) glDisable(GL_CULL_FACE);
    glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT, NULL, (GLsizei)n, 0);
    if (culling) glEnable(GL_CULL_FACE);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    glBindVertexArray(0);
    r->stats.gl_draw_calls++;
    if (out) {
        out->triangles += tris;
        out->draw_calls++;
    }
    return nn;
}
