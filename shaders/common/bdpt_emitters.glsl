// The emissive triangles' weights, shared by bdpt_emitters.comp (their CDF) and
// bdpt_generate.comp (the point on the one picked). Needs `geo` (the frame's slot's geometry
// record, geometry_shared.h), and the buffers `emitters` and `materials` declared.

// Emissive triangle e's area times the luminance of its emissive factor: its share of the
// emitters' power (as the reference weighs them).
float emitter_weight(uint e, out vec3 p0, out vec3 p1, out vec3 p2)
{
    uvec4 t = emitters[e].tri;
    p0 = geo.vertices.v[t.x].position.xyz;
    p1 = geo.vertices.v[t.y].position.xyz;
    p2 = geo.vertices.v[t.z].position.xyz;
    float area = 0.5 * length(cross(p1 - p0, p2 - p0));
    return area * rb_luminance(max(materials[t.w].emissive.rgb, vec3(0.0)));
}
