// bdpt, emitter_direct: the emitters' dispatch (common/bdpt_connect.glsl has the bindings).
// Once a frame over the whole split image: for each pixel
// the direct light of every emitter point among the frame's K_v VPLs, (a) with all of them, not
// the sub-image's share, written in image order to two images of its own that the filter adds
// after its kernels. A sub-image's one or two points, spread over the interleave block by the
// direct light's box, blurred every shadow edge of an area light over the block (the Cornell
// box's contact shadows, 2 pixels each way); at every pixel the points draw it sharp, and their
// count, K_v against the sub-image's n_a, enters the balance heuristic against the bundles.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bdpt_connect.glsl"

// How much of the punctual lights' light reaches x1 (normal n1), as a luminance (irradiance /
// pi): through their shadow maps, one texel, hard. The filter's guide: its kernel stops where this
// changes by more than a factor, at a shadow's edge, which a contact shadow shares with the
// indirect light it cuts off (bdpt_filter.comp). The emitters' points are left out: a cache sees
// K_v of them, and their light's noise in a penumbra cut the kernel into bands that the Cornell
// box's indirect light then showed (beauty 0.0107 -> 0.0128 at 128x128).
float direct_guide(vec3 x1, vec3 n1)
{
    float sum = 0.0;
    for (uint j = 0u; j < g.size.z; j++) {
        rb_gpu_light L = lights[j];
        uint kind = uint(L.position.w);
        vec3 l;
        float atten, dist2;
        toward_light(L, x1, l, atten, dist2);
        float cos1 = dot(n1, l);
        if (cos1 <= 0.0 || atten <= 0.0)
            continue;
        int first = int(L.color.w);
        float vis = 1.0;
        if (first >= 0)
            vis = shadow_lookup(uint(first) + (kind == RB_KIND_POINT ? rb_cube_face(-l) : 0u),
                                x1, n1, cos1, false);
        sum += vis * rb_luminance(L.color.rgb) * atten * cos1 / RB_PI;
    }
    return sum;
}

// atan(y / x) for y >= 0, in [0, pi], from arithmetic alone: Abramowitz and Stegun 4.4.49 on
// [0, 1] (error under 2e-8), folded. The drivers' own atan differs in its last bits from one Mesa
// to the next, and the tarball must render another's bits exactly (check-dist).
float angle_of(float y, float x)
{
    float ax = abs(x), hi = max(ax, y);
    float t = hi > 0.0 ? min(ax, y) / hi : 0.0, s = t * t;
    float r = t * (1.0 + s * (-0.3333314528 + s * (0.1999355085 + s * (-0.1420889944 +
                   s * (0.1065626393 + s * (-0.0752896400 + s * (0.0429096138 +
                   s * (-0.0161657367 + s * 0.0028662257))))))));
    if (y > ax)
        r = 0.5 * RB_PI - r;
    return x < 0.0 ? RB_PI - r : r;
}

// Lambert's sum over a triangle whose corners q are given from the shading point, in a space
// where the surface's normal is n: the triangle clipped to n . q > 0 (Sutherland-Hodgman, at most
// 4 corners), then |sum theta_k n . (v_k x v_k+1) / |v_k x v_k+1||, v_k the corners' directions:
// 2 pi times the normalised cosine's integral over the triangle, seen from either side.
float lambert_sum(vec3 q[3], vec3 n)
{
    vec3 c[4];
    int m = 0;
    for (int k = 0; k < 3; k++) {
        vec3 a = q[k], b = q[(k + 1) % 3];
        float da = dot(n, a), db = dot(n, b);
        if (da > 0.0)
            c[m++] = a;
        if ((da > 0.0) != (db > 0.0))
            c[m++] = a + (b - a) * (da / (da - db));
    }
    if (m < 3)
        return 0.0;
    float s = 0.0;
    for (int k = 0; k < m; k++) {
        vec3 a = normalize(c[k]), b = normalize(c[(k + 1) % m]);
        vec3 g = cross(a, b);
        float len = length(g);
        if (len > 1e-12)
            s += angle_of(len, dot(a, b)) * dot(n, g) / len;
    }
    return abs(s);
}

// The irradiance at x (normal n) from the frame's emissive triangles, unshadowed, in closed form
// (emit_info.tris, both sides emitting): E = L / 2 times Lambert's sum.
vec3 closed_form_irradiance(vec3 x, vec3 n)
{
    vec3 sum = vec3(0.0);
    uint count = uint(emit_info.info.z);
    for (uint e = 0u; e < count; e++) {
        vec3 q[3] = vec3[3](emit_info.tris[4u * e].xyz - x, emit_info.tris[4u * e + 1u].xyz - x,
                            emit_info.tris[4u * e + 2u].xyz - x);
        sum += emit_info.tris[4u * e + 3u].rgb * (0.5 * lambert_sum(q, n));
    }
    return sum;
}

// The specular lobe rb_ggx draws at a point (normal n, toward the camera v, roughness rough),
// Fresnel left out, as a linearly transformed cosine (Heitz et al. 2016, with a transform that
// keeps the surface's plane; the table tools/ltcfit.c fits): r0 r1 r2 take a direction into the
// cosine's space (the frame of n and v's tangent part, then the fit's inverse, bilinear in the
// table), det is that map's determinant.
struct ltc_lobe {
    vec3 r0, r1, r2;
    float det;
};

ltc_lobe ltc_at(vec3 n, vec3 v, float rough)
{
    float ndv = max(dot(n, v), 1e-4);
    vec3 t1 = v - n * dot(n, v);
    float tl = length(t1);
    // At normal incidence the lobe is round: any tangent.
    t1 = tl > 1e-6 ? t1 / tl : normalize(cross(n, abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0)
                                                                   : vec3(0.0, 1.0, 0.0)));
    vec3 t2 = cross(n, t1);
    float last = float(RB_LTC_SIZE - 1);
    vec2 at = vec2(clamp(rough, 0.0, 1.0), sqrt(clamp(1.0 - ndv, 0.0, 1.0))) * last;
    ivec2 i = min(ivec2(at), ivec2(RB_LTC_SIZE - 2));
    vec2 f = at - vec2(i);
    int e = i.y * RB_LTC_SIZE + i.x;
    vec4 m = mix(mix(ltc[e], ltc[e + 1], f.x),
                 mix(ltc[e + RB_LTC_SIZE], ltc[e + RB_LTC_SIZE + 1], f.x), f.y);
    return ltc_lobe(m.x * t1 + m.y * n, t2, m.z * t1 + m.w * n, abs(m.x * m.w - m.y * m.z));
}

// The fitted density toward the unit direction d: the cosine's at d's image, times the map's
// Jacobian.
float ltc_density(ltc_lobe t, vec3 d)
{
    vec3 o = vec3(dot(t.r0, d), dot(t.r1, d), dot(t.r2, d));
    float len = length(o);
    return max(o.z, 0.0) * t.det / (RB_PI * len * len * len * len);
}

// The integral of the lobe's density times the emitted radiance over the frame's emissive
// triangles seen from x, unshadowed, in closed form: each triangle taken into the cosine's space,
// whose normal is z, then Lambert's sum divided by 2 pi; both sides emitting, as the
// irradiance's.
vec3 ltc_emitters(ltc_lobe t, vec3 x)
{
    vec3 sum = vec3(0.0);
    uint count = uint(emit_info.info.z);
    for (uint k = 0u; k < count; k++) {
        vec3 q[3];
        for (int j = 0; j < 3; j++) {
            vec3 d = emit_info.tris[4u * k + uint(j)].xyz - x;
            q[j] = vec3(dot(t.r0, d), dot(t.r1, d), dot(t.r2, d));
        }
        sum += emit_info.tris[4u * k + 3u].rgb * lambert_sum(q, vec3(0.0, 0.0, 1.0));
    }
    return sum / (2.0 * RB_PI);
}

// The point of x's surface (normal n) at the centre of x's pixel px, where x is the cache's sample
// (the centre plus pc.offset.xy): along each axis, moved toward the centre by the offset's share
// of the way to the neighbouring sample on that side, where that sample lies on x's plane (within
// a thousandth of its distance; normal within 0.999); not moved along an axis where it does not,
// nor beyond the image. At the edge of a surface the centre may see another (the Cornell box's
// light quad in front of the ceiling behind it), and x's plane there is hidden from the camera.
vec3 at_pixel_centre(vec3 x, vec3 n, ivec2 px, ivec2 sub, int grid)
{
    vec3 c = x;
    for (int axis = 0; axis < 2; axis++) {
        float o = pc.offset[axis];
        if (o == 0.0)
            continue;
        ivec2 q = px;
        q[axis] += o > 0.0 ? -1 : 1;
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, imageSize(e_diffuse))))
            continue;
        ivec2 sq = (q % grid) * sub + q / grid;
        vec4 pq = imageLoad(s_position, sq);
        vec3 d = pq.xyz - x;
        if (!(pq.w > 0.0) || abs(dot(n, d)) > 1e-3 * length(d) ||
            dot(imageLoad(s_normal, sq).xyz, n) < 0.999)
            continue;
        c += abs(o) * d;
    }
    return c;
}

// The emitters' dispatch for split texel sp: the direct light of each of the frame's K_v VPLs
// that is a point on an emitter, at the pixel sp holds, weighed against the n_b bundles of the
// pixel's sub-image that find the emitter (rb_bdpt_balance with counts K_v and n_b). Where the
// frame's emitters are few untextured triangles (emit_info.info.z), it is all of their light, in
// closed form times a ratio of the points' estimates (the ratio estimator of Heitz et al. 2018):
// the diffuse part is the triangles' irradiance times the points' shadowed share of theirs; the
// specular part the integral of the lobe's fit over the triangles (ltc_emitters) times the
// points' estimate of the lobe's light, shadowed and with Fresnel, over their estimate of that
// integral, which also takes out the fit's error (at a grazing angle the fit is off by tens of
// percent, and the lobe's mean Fresnel twice the Fresnel toward a light off its peak). The
// points' light near an emitter is a spot per point (the Cornell box's ceiling beside the light
// quad, lit by its back 0.9 units below), and the closed forms draw the emitter's shape; the
// points keep the shadows' say and the lobe's finer shape (the box's direct layer: relMSE
// 0.0021 with the points' own specular light, 0.0015 with its closed form). The closed form is
// taken at the pixel's centre (at_pixel_centre), where the reference and the G-buffer take the
// pixel, not at the cache's subpixel sample: behind the light quad's far edge it changes by
// orders of magnitude within a pixel (the bench's classic view at 128x128: relMSE 0.0189 at the
// samples, 0.0087 at the centres). A point stands for a = 1 / (K_v p) of the emitter's area (p
// its density) and lights as a disk of that area would: cos cos / (r^2 + a / pi), which near the
// emitter stays below the emitter's own radiance, as an area light's does, where a point's
// 1 / r^2 threw a bright dot on a surface just beside it (the Cornell box's ceiling around the
// quad that hangs 0.9 units below it).
void emitters(ivec2 sp)
{
    ivec2 sub = ivec2(pc.region.zw);
    int n = int(pc.frame.w);
    ivec2 px = (sp % sub) * n + sp / sub;
    if (any(greaterThanEqual(px, imageSize(e_diffuse))))
        return;
    vec3 dd = vec3(0.0), ds = vec3(0.0);
    vec4 pos = imageLoad(s_position, sp);
    uint strategies = pc.index.w;
    if (pos.w > 0.0 && strategies != RB_BDPT_BUNDLE) {
        vec3 x1 = pos.xyz;
        vec4 nr = imageLoad(s_normal, sp);
        vec4 fr = imageLoad(s_fresnel, sp);
        vec3 n1 = nr.xyz, f0 = fr.rgb, v1 = normalize(g.camera_pos.xyz - x1);
        vec3 ng1 = rb_oct_decode(imageLoad(s_geometric, sp).xy);
        float rough = nr.w, f90 = fr.a;
        uint k_v = uint(pc.frame.y), k_b = uint(pc.frame.z), count = uint(n * n);
        uint s = uint((sp.y / sub.y) * n + sp.x / sub.x);
        float n_b = float(rb_bdpt_share(k_b, s, count)), n_a = pc.frame.y;
        bool closed = closed_form();
        ltc_lobe lobe = closed ? ltc_at(n1, v1, rough)
                               : ltc_lobe(vec3(0.0), vec3(0.0), vec3(0.0), 0.0);
        vec3 shadowed = vec3(0.0), unshadowed = vec3(0.0);
        vec3 fitted = vec3(0.0), specular_seen = vec3(0.0);
        for (uint j = 0u; j < k_v; j++) {
            if (!(vpls[j].position.w > 0.0) || uint(vpls[j].from.w) != RB_BDPT_VPL_EMITTER)
                continue;
            vec3 l;
            float r2, vis;
            float spread = vpl_area(j);
            vec3 x = from_vpl_unshadowed(j, x1, n1, ng1, strategies == RB_BDPT_VPL, spread, l, r2,
                                         vis);
            if (!any(greaterThan(x, vec3(0.0))))
                continue;
            if (closed) {
                vec3 F;
                float D, V;
                unshadowed += x;
                if (!rb_ggx(n1, v1, l, f0, f90, rough, F, D, V))
                    continue;
                fitted += ltc_density(lobe, l) * x / max(dot(n1, l), 1e-6);
                if (vis > 0.0) {
                    shadowed += (vec3(1.0) - F) / RB_PI * x;
                    specular_seen += F * D * V * x;
                }
                continue;
            }
            if (!(vis > 0.0))
                continue;
            float w = 1.0;
            if (strategies == RB_BDPT_MIS) {
                float pdf_bundle = rb_bdpt_bundle_density(-dot(vpls[j].normal.xyz, l), r2);
                w = rb_bdpt_balance(n_a, vpls[j].normal.w, n_b, pdf_bundle);
            }
            add(dd, ds, n1, v1, l, f0, f90, rough, x * (w / n_a));
        }
        if (closed) {
            vec3 c = at_pixel_centre(x1, n1, px, sub, n);
            vec3 e = closed_form_irradiance(c, n1);
            bvec3 lit = greaterThan(unshadowed, vec3(0.0));
            dd = mix(vec3(0.0), shadowed / max(unshadowed, vec3(1e-30)) * e, lit);
            // The specular part likewise: the fitted lobe's closed form times the points' ratio
            // of their estimate of the light, shadowed, through the lobe and Fresnel, to their
            // estimate of the closed form (the fit's error and Fresnel go in the ratio).
            ds = specular_seen / max(fitted, vec3(1e-30)) * ltc_emitters(lobe, c) /
                 rb_spec_map(f0);
        }
    }
    // The filter's guide rides in the alpha.
    float guide = pos.w > 0.0 ? direct_guide(pos.xyz, imageLoad(s_normal, sp).xyz) : 0.0;
    imageStore(e_diffuse, px, vec4(dd, guide));
    imageStore(e_specular, px, vec4(ds, 0.0));
}

void main()
{
    ivec2 sp = ivec2(gl_GlobalInvocationID.xy);
    if (all(lessThan(sp, imageSize(s_position))))
        emitters(sp);
}
