/* Synthetic photo sets for the marker map (`mrcheck map`'s tests and
 * `bench map`): tags on a ring of walls and columns with known poses,
 * photos from inside the ring, as projected corners with Gaussian noise or
 * as CPU ray-cast images (exact lens distortion, optical blur, sensor
 * noise) that the real detector reads. No GPU: tags on planes need nothing
 * else. */
#include "mr_bench.h"
#include "mr_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void mr_synth_map_free(mr_synth_map *s) {
    if (!s) return;
    for (int i = 0; i < s->photo_count; i++) {
        if (s->dets) free(s->dets[i]);
        if (s->images) mr_image_free(&s->images[i]);
    }
    free(s->dets);
    free(s->counts);
    free(s->images);
    free(s->world_from_camera);
    mr_marker_map_free(&s->truth);
    memset(s, 0, sizeof *s);
}

/* Grey level of the tag plates at the first hit along the ray o + t d:
 * the black/white tag cells, a white mount around each tag, -1 for none. */
static double ray_value(const mr_marker_map *m, const mr_dmat4 *tfw, const mr_image *imgs, int nimg, mr_dvec3 o,
                        mr_dvec3 d) {
    double best_t = INFINITY, val = -1;
    for (int i = 0; i < m->count; i++) {
        mr_dvec3 lo = mr_m4_point(&tfw[i], o), ld = mr_m4_dir(&tfw[i], d);
        if (fabs(ld.z) < 1e-12) continue;
        double t = -lo.z / ld.z;
        if (!(t > 0 && t < best_t)) continue;
        double s = mr_marker_size(m, &m->tags[i]), plate = s * 10.0 / 8.0;
        double x = lo.x + t * ld.x, y = lo.y + t * ld.y;
        if (fabs(x) > 0.9 * plate || fabs(y) > 0.9 * plate) continue;
        best_t = t;
        int cx = (int)floor((x / plate + 0.5) * 10), cy = (int)floor((y / plate + 0.5) * 10);
        int id = m->tags[i].id;
        if (cx < 0 || cy < 0 || cx >= 10 || cy >= 10 || id >= nimg)
            val = 220;
        else
            val = ((const unsigned char *)imgs[id].data)[cy * imgs[id].width + cx] ? 220 : 30;
    }
    return val;
}

static bool render_photo(const mr_camera *cam, const mr_marker_map *m, const mr_dmat4 *wfc, const mr_image *imgs,
                         int nimg, double noise, mr_rng *rng, mr_image *out, mr_error *err) {
    if (!mr_image_alloc(out, cam->width, cam->height, 1, MR_PIX_U8, err)) return false;
    mr_dmat4 *tfw = malloc((size_t)m->count * sizeof *tfw);
    double *acc = malloc((size_t)cam->width * cam->height * sizeof *acc);
    if (!tfw || !acc) {
        free(tfw);
        free(acc);
        mr_image_free(out);
        return mr_fail(err, MR_ERR_NOMEM, "synth map: out of memory");
    }
    for (int i = 0; i < m->count; i++) tfw[i] = mr_m4_invert_rigid(&m->tags[i].world_from_tag);
    mr_dvec3 o = mr_v3(wfc->m[3], wfc->m[7], wfc->m[11]);
    for (int v = 0; v < cam->height; v++)
        for (int u = 0; u < cam->width; u++) {
            double a = 0;
            for (int sy = 0; sy < 3; sy++)
                for (int sx = 0; sx < 3; sx++) {
                    double uu = u + (sx - 1) / 3.0, vv = v + (sy - 1) / 3.0, x, y, val = 90; /* a grey hall */
                    if (mr_camera_undistort(cam, (uu - cam->cx) / cam->fx, (vv - cam->cy) / cam->fy, &x, &y)) {
                        double b = ray_value(m, tfw, imgs, nimg, o, mr_m4_dir(wfc, mr_v3(x, y, 1)));
                        if (b >= 0) val = b;
                    }
                    a += val;
                }
            acc[(size_t)v * cam->width + u] = a / 9;
        }
    /* [1 2 1] optical blur, then sensor noise. */
    unsigned char *px = out->data;
    for (int v = 0; v < cam->height; v++)
        for (int u = 0; u < cam->width; u++) {
            double s = 0, w = 0;
            for (int dy = -1; dy <= 1; dy++)
                for (int dx = -1; dx <= 1; dx++) {
                    int x = u + dx, y = v + dy;
                    if (x < 0 || y < 0 || x >= cam->width || y >= cam->height) continue;
                    double k = (dx ? 1 : 2) * (dy ? 1 : 2);
                    s += k * acc[(size_t)y * cam->width + x];
                    w += k;
                }
            double g = s / w + noise * mr_rng_normal(rng);
            px[(size_t)v * cam->width + u] = (unsigned char)(g < 0 ? 0 : g > 255 ? 255 : lrint(g));
        }
    free(tfw);
    free(acc);
    return true;
}

bool mr_synth_map_make(const mr_synth_map_params *params, mr_synth_map *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    mr_synth_map_params p = params ? *params : (mr_synth_map_params){MR_SYNTH_MAP_DEFAULTS};
    if (p.tags < 3 || p.tags > 200 || p.photos < 1 || p.photos > 10000 || p.isolated < 0 || p.isolated > 50 ||
        !(p.tag_size > 0) || !(p.corner_noise_px >= 0) || !(p.radius > 0) || p.width < 64 || p.height < 48 ||
        !(p.misdetect >= 0 && p.misdetect <= 1))
        return mr_fail(err, MR_ERR_INVALID, "synth map: parameters out of range");
    mr_rng rng, mis; /* misdetections draw apart: the same set with and without them */
    mr_rng_seed(&rng, p.seed);
    mr_rng_seed(&mis, p.seed ^ 0x9e3779b97f4a7c15ull);
    mr_camera base = mr_demo_camera();
    mr_camera cam = mr_camera_resized(&base, p.width, p.height);
    out->camera = cam;

    int nt = p.tags + p.isolated;
    mr_marker_map *m = &out->truth;
    snprintf(m->family, sizeof m->family, "tag36h11");
    m->tag_size = p.tag_size;
    m->tags = calloc((size_t)nt, sizeof *m->tags);
    if (!m->tags) return mr_fail(err, MR_ERR_NOMEM, "synth map: out of memory");
    m->count = nt;
    /* The ring: tags facing its centre at eye height +-, on walls at the
     * radius +- 10 %, a few degrees of tilt (no two tags coplanar). */
    for (int i = 0; i < p.tags; i++) {
        double th = 2 * M_PI * (i + 0.3 * (mr_rng_uniform(&rng) - 0.5)) / p.tags;
        double r = p.radius * (1 + 0.1 * (mr_rng_uniform(&rng) - 0.5)), h = 1.5 + 0.6 * (mr_rng_uniform(&rng) - 0.5);
        mr_dvec3 c = mr_v3(r * cos(th), h, r * sin(th));
        mr_dvec3 n = mr_v3(cos(th + 0.2 * (mr_rng_uniform(&rng) - 0.5)), 0.15 * (mr_rng_uniform(&rng) - 0.5),
                           sin(th + 0.2 * (mr_rng_uniform(&rng) - 0.5)));
        m->tags[i].id = i;
        m->tags[i].world_from_tag = mr_m4_look_at_cv(c, mr_v3_add(c, n), mr_v3(0, 1, 0));
        if (p.mixed_sizes && i % 3 == 1) m->tags[i].size = 1.5 * p.tag_size;
        m->tags[i].world_from_tag.m[3] += p.offset;
    }
    /* The isolated part: tags in a room of their own, far off. */
    for (int i = 0; i < p.isolated; i++) {
        mr_dvec3 c = mr_v3(p.radius * 20 + 0.6 * i, 1.5, 0);
        m->tags[p.tags + i].id = p.tags + i;
        m->tags[p.tags + i].world_from_tag = mr_m4_look_at_cv(c, mr_v3_add(c, mr_v3(0, 0, 1)), mr_v3(0, 1, 0));
        m->tags[p.tags + i].world_from_tag.m[3] += p.offset;
    }

    int np = p.photos + (p.isolated > 0 ? 2 : 0);
    out->photo_count = np;
    out->world_from_camera = calloc((size_t)np, sizeof *out->world_from_camera);
    out->dets = calloc((size_t)np, sizeof *out->dets);
    out->counts = calloc((size_t)np, sizeof *out->counts);
    if (p.render) out->images = calloc((size_t)np, sizeof *out->images);
    if (!out->world_from_camera || !out->dets || !out->counts || (p.render && !out->images)) {
        mr_synth_map_free(out);
        return mr_fail(err, MR_ERR_NOMEM, "synth map: out of memory");
    }
    mr_image *imgs = NULL;
    int border = 0;
    if (p.render && !mr_demo_tag_images(nt, &imgs, &border, err)) {
        mr_synth_map_free(out);
        return false;
    }
    bool ok = true;
    for (int j = 0; ok && j < np; j++) {
        mr_dmat4 wfc;
        if (j < p.photos) {
            /* Around the ring, looking at a spot of the wall from inside. */
            double th = 2 * M_PI * (j + 0.5 * mr_rng_uniform(&rng)) / p.photos;
            double r = p.radius * (0.3 + 0.5 * mr_rng_uniform(&rng));
            double side = th + M_PI + 0.8 * (mr_rng_uniform(&rng) - 0.5); /* across the room */
            mr_dvec3 eye = mr_v3(r * cos(side), 1.5 + 0.4 * (mr_rng_uniform(&rng) - 0.5), r * sin(side));
            mr_dvec3 at = mr_v3(p.radius * cos(th), 1.5, p.radius * sin(th));
            wfc = mr_m4_look_at_cv(eye, at, mr_v3(0, 1, 0));
        } else {
            mr_dvec3 c = mr_v3(p.radius * 20 + 0.3 * (p.isolated - 1), 1.5, 0);
            mr_dvec3 eye = mr_v3(c.x + (j - p.photos - 0.5) * 0.8, 1.6, -2.0);
            wfc = mr_m4_look_at_cv(eye, c, mr_v3(0, 1, 0));
        }
        wfc.m[3] += p.offset;
        out->world_from_camera[j] = wfc;
        if (p.render) {
            ok = render_photo(&cam, m, &wfc, imgs, nt, p.image_noise, &rng, &out->images[j], err);
            continue;
        }
        /* Projected corners: every tag whose four corners land inside the
         * image, facing the camera, at least min size. */
        out->dets[j] = calloc((size_t)nt, sizeof *out->dets[j]);
        if (!out->dets[j]) {
            ok = mr_fail(err, MR_ERR_NOMEM, "synth map: out of memory");
            break;
        }
        for (int i = 0; i < nt; i++) {
            mr_dvec3 c[4];
            mr_marker_corners_world(m, &m->tags[i], c);
            mr_dvec3 ctr = mr_v3(m->tags[i].world_from_tag.m[3], m->tags[i].world_from_tag.m[7],
                                 m->tags[i].world_from_tag.m[11]);
            mr_dvec3 zt = mr_v3(m->tags[i].world_from_tag.m[2], m->tags[i].world_from_tag.m[6],
                                m->tags[i].world_from_tag.m[10]);
            mr_dvec3 view = mr_v3_sub(ctr, mr_v3(wfc.m[3], wfc.m[7], wfc.m[11]));
            if (mr_v3_dot(view, zt) <= 0.2 * mr_v3_len(view)) continue; /* from behind or grazing */
            mr_detection d = {.id = m->tags[i].id};
            bool in = true;
            for (int k = 0; k < 4 && in; k++) {
                double u, v;
                in = mr_project_point(&cam, &wfc, c[k], &u, &v) && u > 2 && v > 2 && u < cam.width - 3 &&
                     v < cam.height - 3;
                d.corners[k][0] = u + p.corner_noise_px * mr_rng_normal(&rng);
                d.corners[k][1] = v + p.corner_noise_px * mr_rng_normal(&rng);
            }
            if (!in || hypot(d.corners[1][0] - d.corners[0][0], d.corners[1][1] - d.corners[0][1]) < 10) continue;
            out->dets[j][out->counts[j]++] = d;
        }
        /* A misdetection: one sighting gets another tag's id. */
        if (j < p.photos && out->counts[j] > 0 && mr_rng_uniform(&mis) < p.misdetect) {
            int k = (int)(mr_rng_uniform(&mis) * out->counts[j]);
            for (int tries = 0; tries < 20; tries++) {
                int id = (int)(mr_rng_uniform(&mis) * p.tags), dup = 0;
                for (int q = 0; q < out->counts[j]; q++) dup += out->dets[j][q].id == id;
                if (!dup) {
                    out->dets[j][k].id = id;
                    break;
                }
            }
        }
    }
    if (imgs) mr_demo_tag_images_free(imgs, nt);
    if (!ok) mr_synth_map_free(out);
    return ok;
}

bool mr_synth_map_write(const char *dir, const mr_synth_map_params *params, mr_error *err) {
    mr_synth_map_params p = params ? *params : (mr_synth_map_params){MR_SYNTH_MAP_SET_DEFAULTS};
    p.render = true;
    char path[4096];
    mr_path_join(dir, "images", path, sizeof path);
    if (mr_file_exists(path)) return mr_fail(err, MR_ERR_INVALID, "%s already exists (never overwritten)", path);
    if (!mr_mkdirs(path, err)) return false;
    mr_synth_map s;
    if (!mr_synth_map_make(&p, &s, err)) return false;
    bool ok = true;
    for (int j = 0; ok && j < s.photo_count; j++) {
        char name[64];
        snprintf(name, sizeof name, "images/photo_%03d.png", j);
        mr_path_join(dir, name, path, sizeof path);
        ok = mr_image_save_png(path, &s.images[j], err);
    }
    /* The same photos as a video (`mrcheck map --video`). */
    if (ok && s.photo_count > 0) {
        mr_path_join(dir, "photos.avi", path, sizeof path);
        mr_video_writer *vw = mr_video_writer_open(path, s.images[0].width, s.images[0].height, 5.0, err);
        ok = vw != NULL;
        for (int j = 0; ok && j < s.photo_count; j++) ok = mr_video_writer_add(vw, &s.images[j], err);
        if (ok) ok = mr_video_writer_close(&vw, err);
        else mr_video_writer_abort(&vw);
    }
    if (ok) {
        cJSON *c = mr_camera_to_json(&s.camera);
        mr_path_join(dir, "camera.json", path, sizeof path);
        ok = mr_json_save(path, c, err);
        cJSON_Delete(c);
    }
    if (ok) {
        cJSON *t = mr_marker_map_to_json(&s.truth);
        mr_path_join(dir, "truth.json", path, sizeof path);
        ok = mr_json_save(path, t, err);
        cJSON_Delete(t);
    }
    if (ok) {
        /* Four tag centres as a total station would give them (exact here;
         * sigma 1 mm). */
        cJSON *j = cJSON_CreateObject(), *pts = cJSON_AddArrayToObject(j, "points");
        cJSON_AddNumberToObject(j, "sigma", 0.001);
        int n = s.truth.count < 4 ? s.truth.count : 4;
        for (int q = 0; q < n; q++) {
            const mr_marker *m = &s.truth.tags[q * (s.truth.count / n)];
            cJSON *o = cJSON_CreateObject();
            char nm[32];
            snprintf(nm, sizeof nm, "P%d", q + 1);
            cJSON_AddStringToObject(o, "name", nm);
            cJSON_AddNumberToObject(o, "tag", m->id);
            cJSON_AddStringToObject(o, "corner", "centre");
            double xyz[3] = {m->world_from_tag.m[3], m->world_from_tag.m[7], m->world_from_tag.m[11]};
            cJSON_AddItemToObject(o, "xyz", mr_json_from_doubles(xyz, 3));
            cJSON_AddItemToArray(pts, o);
        }
        mr_path_join(dir, "control.json", path, sizeof path);
        ok = mr_json_save(path, j, err);
        cJSON_Delete(j);
    }
    mr_synth_map_free(&s);
    return ok;
}
