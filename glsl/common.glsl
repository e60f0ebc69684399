// Shared by the renderer's shaders: transfer-function and preintegration-table lookups,
// opacity correction. Equation numbers refer to the thesis (Magnus & Bruckner).
#ifndef REFRAKT_COMMON_GLSL
#define REFRAKT_COMMON_GLSL

// TF_SAMPLES and PREINT_SIZE are macros from src/render/limits.rs (build.rs).

// Post-interpolative TF lookup: hardware-filtered, sample i of TF_SAMPLES sits at
// s = i / (TF_SAMPLES - 1), so s maps to texel centre s * (N - 1) + 0.5.
float tf_coord(float s) {
    return (clamp(s, 0.0, 1.0) * float(TF_SAMPLES - 1u) + 0.5) / float(TF_SAMPLES);
}

// Opacity correction for a step of `ratio` reference sample distances (eq. 3.13).
float correct_opacity(float alpha, float ratio) {
    return 1.0 - pow(max(1.0 - alpha, 0.0), ratio);
}

// Medium colour for a step of `ratio` reference distances: the multiplicative integral of
// a constant medium over the step is m^ratio (eq. 4.15 and the power rule).
vec3 correct_medium(vec3 m, float ratio) {
    return pow(max(m, vec3(0.0)), vec3(ratio));
}

// Preintegration table coordinate of (front, back) scalar values: entry (i, j) holds
// front = i / 255, back = j / 255.
vec2 preint_coord(float front, float back) {
    return (clamp(vec2(front, back), 0.0, 1.0) * float(PREINT_SIZE - 1u) + 0.5) / float(PREINT_SIZE);
}

// The eight voxels of the trilinear cell around texture coordinate t in a volume of
// `dims` voxels, fetched unfiltered (clamp to edge; c[k] at offset (k & 1, (k >> 1) & 1,
// k >> 2)), and t's fraction f within the cell: for interpolants and their exact
// derivatives computed in f32 (the sweep's value_gradient, ray_equation.glsl).
void cell_voxels(sampler3D vol, vec3 t, vec3 dims, out float c[8], out vec3 f) {
    vec3 x = t * dims - 0.5;
    ivec3 i = ivec3(floor(x));
    f = x - vec3(i);
    ivec3 hi = ivec3(dims) - 1;
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, k >> 2);
        c[k] = texelFetch(vol, clamp(i + o, ivec3(0), hi), 0).r;
    }
}

#endif
