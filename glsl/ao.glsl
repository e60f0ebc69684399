// Volumetric ambient occlusion from the 3D summed-area table of the extinction volume
// (Schlegel et al., the SAT method Ament et al. compare against; render/ao). The ambient
// light reaching x is taken as the transmittance over a radius R around it, the extinction
// of each distance estimated by the average over nested cubes of voxels centred on x's
// voxel: the voxel itself (reaching 0.5 voxel), then cubes of half-size 1, 2, 4, ...
// AO_SHELLS-1 voxels (reaching r + 0.5). Each shell (a cube less the one inside it)
// contributes its mean extinction times the radial distance it spans:
//
//   tau(x) = 0.5 sigma(x) + sum_k  mean_{C_k \ C_(k-1)} sigma  * (r_k - r_(k-1)),
//   AO(x) = exp(-tau(x)),   R = 2^(AO_SHELLS-1) + 0.5 voxels,
//
// which is exp(-sigma R) inside a homogeneous medium, and counts the outside of the volume
// as empty (a point at a face of a homogeneous block sees about half its shells filled).
// The shell sums are exact differences of 64-bit fixed-point box sums (sat3d.glsl).
//
// Before including: sat3d.glsl with SAT3D_LOAD, SAT3D_DIMS, SAT3D_INV_SCALE defined.

// Transmittance of the ambient light at texture coordinate `tex`, over `shells` shells.
float ao_transmittance(vec3 tex, int shells) {
    ivec3 c = ivec3(floor(tex * vec3(SAT3D_DIMS)));
    uvec2 inner = sat3d_box_sum(c, c);
    float inner_volume = 1.0;
    float tau = 0.5 * sat3d_to_float(inner) * SAT3D_INV_SCALE;
    float reach = 0.5;
    for (int k = 0; k < shells; ++k) {
        int r = 1 << k;
        uvec2 outer = sat3d_box_sum(c - r, c + r);
        float side = float(2 * r + 1);
        float outer_volume = side * side * side;
        float shell = sat3d_to_float(sat3d_sub(outer, inner)) * SAT3D_INV_SCALE
                    / (outer_volume - inner_volume);
        float next = float(r) + 0.5;
        tau += shell * (next - reach);
        inner = outer;
        inner_volume = outer_volume;
        reach = next;
    }
    return exp(-tau);
}
