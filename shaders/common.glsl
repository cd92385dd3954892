// Shared helpers, pulled in with #include "common.glsl".

// Uniform locations shared by the full-screen passes.
#define LOC_SIZE 0

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(0.04045, c));
}
vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
// OpenCV pixel coordinates of this fragment (centre of the top-left pixel is
// 0,0). Render targets are stored top row first, so no flip is needed.
vec2 cv_pixel() { return gl_FragCoord.xy - 0.5; }
