// The Henyey-Greenstein phase function, shared by the scattering models (single.comp,
// ambient.comp, eikonal_view.comp).
#ifndef REFRAKT_PHASE_GLSL
#define REFRAKT_PHASE_GLSL

// 4 pi times the Henyey-Greenstein phase function of anisotropy g at the cosine of the
// scattering angle (between the light's travel and the scattered light's): mean 1 over
// the sphere of directions, so isotropic scattering (g = 0) is 1 everywhere.
float hg4pi(float cos_theta, float g) {
    float d = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (d * sqrt(d));
}

#endif
