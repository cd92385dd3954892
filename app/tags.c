/* AprilTag images from the apriltag library, for the demo's tag plates. */
#include "app.h"

#include <stdlib.h>
#include <string.h>

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>

bool app_tag_images(int count, mr_image **out, int *border, mr_error *err) {
    *out = NULL;
    apriltag_family_t *fam = tag36h11_create();
    if (!fam) return mr_fail(err, MR_ERR_NOMEM, "cannot create the tag36h11 family");
    if (count > (int)fam->ncodes) count = (int)fam->ncodes;
    mr_image *imgs = calloc((size_t)count, sizeof *imgs);
    bool ok = imgs != NULL;
    for (int i = 0; ok && i < count; i++) {
        image_u8_t *im = apriltag_to_image(fam, i);
        ok = im && mr_image_alloc(&imgs[i], im->width, im->height, 1, MR_PIX_U8, err);
        for (int y = 0; ok && y < im->height; y++)
            memcpy((unsigned char *)imgs[i].data + (size_t)y * im->width, im->buf + (size_t)y * im->stride,
                   (size_t)im->width);
        if (im) image_u8_destroy(im);
    }
    /* The image spans total_width cells; the black square spans
     * width_at_border; the rest is the white quiet zone around it. */
    *border = (fam->total_width - fam->width_at_border) / 2;
    tag36h11_destroy(fam);
    if (!ok) {
        app_tag_images_free(imgs, count);
        return err && err->code ? false : mr_fail(err, MR_ERR_NOMEM, "cannot render AprilTag images");
    }
    *out = imgs;
    return true;
}

void app_tag_images_free(mr_image *imgs, int count) {
    if (!imgs) return;
    for (int i = 0; i < count; i++) mr_image_free(&imgs[i]);
    free(imgs);
}
