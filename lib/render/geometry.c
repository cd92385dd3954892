/* Geometry: the scene's meshes and textures on the GPU, and drawing them
 * into the G-buffer layout with camera-relative matrices. */
#include "render_internal.h"

#include <stdlib.h>
#include <string.h>

static GLuint upload_buffer(const void *data, size_t bytes) {
    GLuint b;
    glCreateBuffers(1, &b);
    glNamedBufferStorage(b, (GLsizeiptr)bytes, data, 0);
    return b;
}


void mr_geometry_free(mr_renderer *r) {
    for (int32_t i = 0; i < r->mesh_count; i++) {
        glDeleteVertexArrays(1, &r->meshes[i].vao);
        glDeleteBuffers(3, r->meshes[i].vbo);
        glDeleteBuffers(1, &r->meshes[i].ibo);
    }
    free(r->meshes);
    r->meshes = NULL;
    r->mesh_count = 0;
    if (r->textures) glDeleteTextures(r->texture_count, r->textures);
    free(r->textures);
    r->textures = NULL;
    r->texture_count = 0;
    r->scene = NULL;
}


bool mr_geometry_upload(mr_renderer *r, const mr_scene *s, mr_error *err) {
    r->meshes = calloc((size_t)s->mesh_count + 1, sizeof *r->meshes);
    r->textures = calloc((size_t)s->texture_count + 1, sizeof *r->textures);
    if (!r->meshes || !r->textures) {
        mr_geometry_free(r);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory uploading the scene");
    }
    /* UVs are uploaded only for meshes whose material samples a texture. */
    for (int32_t i = 0; i < s->mesh_count; i++) {
        const mr_mesh *m = &s->meshes[i];
        gl_mesh *g = &r->meshes[i];
        bool textured = m->uvs && m->material >= 0 && m->material < s->material_count &&
                        s->materials[m->material].base_color_texture >= 0;
        glCreateVertexArrays(1, &g->vao);
        g->vbo[0] = upload_buffer(m->positions, (size_t)m->vertex_count * 12);
        g->vbo[1] = upload_buffer(m->normals, (size_t)m->vertex_count * 12);
        glVertexArrayVertexBuffer(g->vao, 0, g->vbo[0], 0, 12);
        glVertexArrayVertexBuffer(g->vao, 1, g->vbo[1], 0, 12);
        for (GLuint a = 0; a < 2; a++) {
            glEnableVertexArrayAttrib(g->vao, a);
            glVertexArrayAttribFormat(g->vao, a, 3, GL_FLOAT, GL_FALSE, 0);
            glVertexArrayAttribBinding(g->vao, a, a);
        }
        if (textured) {
            g->vbo[2] = upload_buffer(m->uvs, (size_t)m->vertex_count * 8);
            glVertexArrayVertexBuffer(g->vao, 2, g->vbo[2], 0, 8);
            glEnableVertexArrayAttrib(g->vao, 2);
            glVertexArrayAttribFormat(g->vao, 2, 2, GL_FLOAT, GL_FALSE, 0);
            glVertexArrayAttribBinding(g->vao, 2, 2);
        }
        g->ibo = upload_buffer(m->indices, (size_t)m->index_count * 4);
        glVertexArrayElementBuffer(g->vao, g->ibo);
        g->index_count = m->index_count;
    }
    r->mesh_count = s->mesh_count;
    for (int32_t i = 0; i < s->texture_count; i++) {
        const mr_texture *t = &s->textures[i];
        if (!t->image.data || t->image.channels != 4 || t->image.type != MR_PIX_U8) {
            mr_geometry_free(r);
            return mr_fail(err, MR_ERR_INVALID, "texture %d is not RGBA8", (int)i);
        }
        int w = t->image.width, h = t->image.height, levels = 1;
        while ((w >> levels) > 0 || (h >> levels) > 0) levels++;
        GLuint tex;
        glCreateTextures(GL_TEXTURE_2D, 1, &tex);
        glTextureStorage2D(tex, levels, GL_SRGB8_ALPHA8, w, h);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTextureSubImage2D(tex, 0, 0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, t->image.data);
        glGenerateTextureMipmap(tex);
        glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, t->nearest ? GL_NEAREST : GL_LINEAR);
        r->textures[i] = tex;
    }
    r->texture_count = s->texture_count;
    r->scene = s;
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) {
        mr_geometry_free(r);
        return mr_fail(err, MR_ERR_GL, "GL error 0x%x while uploading the scene", e);
    }
    return true;
}


void mr_geometry_draw(frame *f, uint32_t layer_mask) {
    mr_renderer *r = f->r;
    const mr_scene *s = r->scene;
    if (!s) return;
    glUseProgram(r->prog_gbuffer);
    float proj[16];
    mr_gl_projection(&f->cam, f->near_plane, proj);
    glUniformMatrix4fv(2, 1, GL_FALSE, proj);
    for (int32_t ni = 0; ni < s->node_count; ni++) {
        const mr_node *n = &s->nodes[ni];
        if (n->mesh_first < 0 || n->mesh_count <= 0) continue;
        if (!(layer_mask & (1u << n->layer))) continue;
        mr_dmat4 cam_from_node = mr_m4_mul(&f->cam_from_world, &n->world);
        glUniform2ui(5, (GLuint)ni + 1, n->layer);
        for (int32_t k = 0; k < n->mesh_count; k++) {
            int32_t mi = n->mesh_first + k;
            if (mi >= r->mesh_count) break;
            const mr_mesh *m = &s->meshes[mi];
            /* Camera-relative in double, then float: this is what keeps a
             * scene 1e7 units from the origin as sharp as one at it. */
            mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
            mr_dmat4 mv = mr_m4_mul(&cam_from_node, &T);
            mr_dmat4 inv;
            float mvf[16], nm[9];
            mr_m4_to_gl(&mv, mvf);
            if (!mr_m4_invert(&mv, &inv)) continue; /* degenerate (zero scale): nothing to draw */
            for (int rr = 0; rr < 3; rr++)
                for (int cc = 0; cc < 3; cc++) nm[cc * 3 + rr] = (float)inv.m[cc * 4 + rr]; /* transpose */
            glUniformMatrix4fv(0, 1, GL_FALSE, mvf);
            glUniformMatrix3fv(1, 1, GL_FALSE, nm);
            float color[4] = {0.7f, 0.7f, 0.7f, 1.0f};
            int has_tex = 0;
            if (m->material >= 0 && m->material < s->material_count) {
                const mr_material *mat = &s->materials[m->material];
                memcpy(color, mat->base_color, sizeof color);
                if (mat->base_color_texture >= 0 && mat->base_color_texture < r->texture_count && m->uvs) {
                    glBindTextureUnit(0, r->textures[mat->base_color_texture]);
                    has_tex = 1;
                }
            }
            glUniform4fv(3, 1, color);
            glUniform1i(4, has_tex);
            glBindVertexArray(r->meshes[mi].vao);
            glDrawElements(GL_TRIANGLES, (GLsizei)r->meshes[mi].index_count, GL_UNSIGNED_INT, NULL);
            f->out->triangles += r->meshes[mi].index_count / 3;
            f->out->draw_calls++;
        }
    }
    glBindVertexArray(0);
}

