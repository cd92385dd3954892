// CIE L*a*b* helpers for the ghosting passes (D65 white and sRGB primaries,
// the constants OpenCV's cvtColor uses, so tests can compare against it).
// Inputs are linear RGB. Out-of-gamut values (negative or above 1) stay
// finite: the cube root is only taken of positive values, the CIE linear
// branch covers everything at or below delta^3, negatives included.

const vec3 LAB_WHITE = vec3(0.950456, 1.0, 1.088754);
const float LAB_DELTA = 6.0 / 29.0;

const mat3 LAB_RGB_TO_XYZ = mat3(0.412453, 0.212671, 0.019334,   // column R
                                 0.357580, 0.715160, 0.119193,   // column G
                                 0.180423, 0.072169, 0.950227);  // column B

float lab_f(float t) {
    return t > LAB_DELTA * LAB_DELTA * LAB_DELTA ? pow(t, 1.0 / 3.0)
                                                 : t / (3.0 * LAB_DELTA * LAB_DELTA) + 4.0 / 29.0;
}
float lab_finv(float f) {
    return f > LAB_DELTA ? f * f * f : 3.0 * LAB_DELTA * LAB_DELTA * (f - 4.0 / 29.0);
}
vec3 rgb_to_lab(vec3 rgb) {
    vec3 xyz = (LAB_RGB_TO_XYZ * rgb) / LAB_WHITE;
    float fx = lab_f(xyz.x), fy = lab_f(xyz.y), fz = lab_f(xyz.z);
    return vec3(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz));
}
vec3 lab_to_rgb(vec3 lab) {
    float fy = (lab.x + 16.0) / 116.0;
    vec3 xyz = vec3(lab_finv(fy + lab.y / 500.0), lab_finv(fy), lab_finv(fy - lab.z / 200.0)) * LAB_WHITE;
    return inverse(LAB_RGB_TO_XYZ) * xyz;
}

// sRGB encoding for compute shaders (common.glsl needs gl_FragCoord).
vec3 ghost_linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
