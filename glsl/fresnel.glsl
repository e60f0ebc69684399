// Fresnel reflectance (eq. 4.12) for the sweep's faces and highlights and the eikonal
// model's viewing rays (glsl/sweep_plane.glsl, glsl/eikonal_view.comp).
#ifndef REFRAKT_FRESNEL_GLSL
#define REFRAKT_FRESNEL_GLSL

// Cook-Torrance Fresnel for unpolarised light (eq. 4.12; the thesis prints the bracket's
// square and (g+c) as (g+2) wrongly). eta_ratio = eta_t / eta_i; total reflection where g
// would be imaginary.
float fresnel(float c, float eta_ratio) {
    float g2 = eta_ratio * eta_ratio - 1.0 + c * c;
    if (g2 <= 0.0) return 1.0;
    float g = sqrt(g2);
    float a = (g - c) / (g + c);
    float b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    return 0.5 * a * a * (1.0 + b * b);
}

// Fresnel reflectance of a face between eta_a and eta_b for a ray whose v = eta dx/ds has
// the tangential part vt (kept across the face, Snell): F is the same both ways through a
// face (reciprocity), from the angle on its low side; 1 beyond the critical angle.
float face_fresnel(float vt, float eta_a, float eta_b) {
    float lo = min(eta_a, eta_b), hi = max(eta_a, eta_b);
    float sin_lo = vt / lo;
    if (sin_lo >= 1.0) return 1.0;
    return fresnel(sqrt(1.0 - sin_lo * sin_lo), hi / lo);
}

#endif
