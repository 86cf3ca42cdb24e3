/* The rig and mesh data of the C API (issue 18): an importer written only against the header
 * rebuilds the rigged body the GLB describes. From the bone names, parents, rest transforms,
 * local rotations and root translation it composes the posed skeleton (forward kinematics, as a
 * glTF reader does) and checks it against the library's posed heads within 0.1 mm; from the rig's
 * rest vertices and 53-bone skin weights it skins the posed mesh and checks it against the rig's
 * posed vertices within 0.1 mm; the rest transforms put the joint-named bones on the mesh's
 * joints. For every naming, A- and T-pose rests and both origins. Also UVs, normals, faces, and
 * the named errors. Built and run by ctest under ASan + UBSan. */
#include <sketchbody.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "c_check.h"

#define NB SKB_NUM_RIG_BONES

typedef struct { double x, y, z, w; } quat;
typedef struct { double r[4]; double t[3]; } xform; /* rotation quaternion (x, y, z, w), translation */

static quat qmul(quat a, quat b) {
    quat q = {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
              a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
    return q;
}

static void qrot(quat q, const double v[3], double out[3]) {
    quat p = {v[0], v[1], v[2], 0.0}, c = {-q.x, -q.y, -q.z, q.w};
    quat r = qmul(qmul(q, p), c);
    out[0] = r.x;
    out[1] = r.y;
    out[2] = r.z;
}

/* Global transform of every bone: parent · T(t) · R(q), the glTF node rule. */
static void forward(const int32_t *parents, const double (*t)[3], const quat *q, quat *gq, double (*gt)[3]) {
    for (int b = 0; b < (int)NB; ++b) {
        if (parents[b] < 0) {
            gq[b] = q[b];
            memcpy(gt[b], t[b], sizeof gt[b]);
        } else {
            const int p = parents[b];
            double d[3];
            qrot(gq[p], t[b], d);
            gq[b] = qmul(gq[p], q[b]);
            for (int k = 0; k < 3; ++k) gt[b][k] = gt[p][k] + d[k];
        }
    }
}

static double dist3(const double *a, const double *b) {
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

static const char *kJoints[15] = {"head",   "neck",  "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist",
                                  "pelvis", "r_hip", "r_knee",     "r_ankle", "l_hip",   "l_knee",     "l_ankle"};

/* One rig: reconstruct and compare. Returns the worst skeleton and skin errors through the
 * pointers (metres). */
static int named_joints = 0;
static double worst_posed_joint = 0.0;

static void check_rig(const struct skb_mesh *mesh, uint32_t naming, uint32_t rest, uint32_t origin, size_t nv,
                      const double *rest_joints, const double *posed_joints, double *worst_heads, double *worst_skin,
                      double *worst_rest_joint) {
    struct skb_export_options *opts = NULL;
    CHECK(skb_export_options_new(&opts) == SKB_OK);
    CHECK(skb_export_options_set_naming(opts, naming) == SKB_OK);
    CHECK(skb_export_options_set_rest_pose(opts, rest) == SKB_OK);
    CHECK(skb_export_options_set_origin(opts, origin) == SKB_OK);
    struct skb_rig *rig = NULL;
    CHECK(skb_rig_new_from_mesh(mesh, opts, &rig) == SKB_OK);
    skb_export_options_free(opts);
    if (rig == NULL) return;

    size_t nb = 0;
    CHECK(skb_rig_bone_count(rig, &nb) == SKB_OK && nb == NB);
    char names[NB][64];
    for (size_t b = 0; b < NB; ++b) CHECK(skb_rig_copy_bone_name(rig, b, names[b], sizeof names[b]) == SKB_OK);
    const char *root = naming == SKB_NAMING_PROJECT ? "root" : naming == SKB_NAMING_MIXAMO ? "mixamorig:Root" : "root";
    const char *hips = naming == SKB_NAMING_PROJECT ? "pelvis" : naming == SKB_NAMING_MIXAMO ? "mixamorig:Hips" : "pelvis";
    CHECK(strcmp(names[0], root) == 0);
    CHECK(strcmp(names[1], hips) == 0);
    for (size_t a = 0; a < NB; ++a)
        for (size_t b = a + 1; b < NB; ++b) CHECK(strcmp(names[a], names[b]) != 0);

    int32_t parents[NB];
    CHECK(skb_rig_copy_parents(rig, parents, NB) == SKB_OK);
    CHECK(parents[0] == -1);
    for (int b = 1; b < (int)NB; ++b) CHECK(parents[b] >= 0 && parents[b] < b);

    double rt[NB * SKB_RIG_TRANSFORM_LEN], lr[NB * 4], root_t[3], heads[NB * 3], offset[3];
    CHECK(skb_rig_copy_rest_transforms(rig, rt, sizeof rt / sizeof rt[0]) == SKB_OK);
    CHECK(skb_rig_copy_local_rotations(rig, lr, sizeof lr / sizeof lr[0]) == SKB_OK);
    CHECK(skb_rig_copy_root_translation(rig, root_t, 3) == SKB_OK);
    CHECK(skb_rig_copy_posed_heads(rig, heads, sizeof heads / sizeof heads[0]) == SKB_OK);
    CHECK(skb_rig_copy_offset(rig, offset, 3) == SKB_OK);
    if (origin == SKB_ORIGIN_PELVIS) CHECK(root_t[0] == 0.0 && root_t[1] == 0.0 && root_t[2] == 0.0);

    double t[NB][3];
    quat rest_q[NB], posed_q[NB], rest_gq[NB], posed_gq[NB];
    double rest_gt[NB][3], posed_gt[NB][3];
    for (size_t b = 0; b < NB; ++b) {
        const double *r = rt + SKB_RIG_TRANSFORM_LEN * b;
        memcpy(t[b], r, sizeof t[b]);
        rest_q[b] = (quat){r[3], r[4], r[5], r[6]};
        posed_q[b] = (quat){lr[4 * b], lr[4 * b + 1], lr[4 * b + 2], lr[4 * b + 3]};
        CHECK(fabs(rest_q[b].x * rest_q[b].x + rest_q[b].y * rest_q[b].y + rest_q[b].z * rest_q[b].z +
                   rest_q[b].w * rest_q[b].w - 1.0) < 1e-9);
    }
    forward(parents, (const double (*)[3])t, rest_q, rest_gq, rest_gt);
    for (int k = 0; k < 3; ++k) t[0][k] += root_t[k];
    forward(parents, (const double (*)[3])t, posed_q, posed_gq, posed_gt);

    /* The posed skeleton the importer built against the library's. */
    for (size_t b = 0; b < NB; ++b) {
        const double e = dist3(posed_gt[b], heads + 3 * b);
        if (e > *worst_heads) *worst_heads = e;
    }
    /* In the A-pose rest, bones named after a canonical joint start on that joint (+ offset). */
    if (naming == SKB_NAMING_PROJECT && rest == SKB_REST_A_POSE) {
        for (int j = 1; j < 15; ++j) {
            for (size_t b = 0; b < NB; ++b) {
                if (strcmp(names[b], kJoints[j]) != 0) continue;
                const double want[3] = {rest_joints[3 * j] + offset[0], rest_joints[3 * j + 1] + offset[1],
                                        rest_joints[3 * j + 2] + offset[2]};
                const double e = dist3(rest_gt[b], want);
                if (e > *worst_rest_joint) *worst_rest_joint = e;
                ++named_joints;
                /* ... and the importer's posed skeleton puts them on skb_mesh_pose's joints. */
                const double posed[3] = {posed_joints[3 * j] + offset[0] + root_t[0],
                                         posed_joints[3 * j + 1] + offset[1] + root_t[1],
                                         posed_joints[3 * j + 2] + offset[2] + root_t[2]};
                const double ep = dist3(posed_gt[b], posed);
                if (ep > worst_posed_joint) worst_posed_joint = ep;
            }
        }
    }

    /* Linear blend skinning with the rig's data: x' = Σ w_b · G_posed,b · G_rest,b⁻¹ · x. */
    float *rv = malloc(3 * nv * sizeof *rv), *pv = malloc(3 * nv * sizeof *pv), *w = malloc(4 * nv * sizeof *w);
    uint32_t *bi = malloc(4 * nv * sizeof *bi);
    CHECK(skb_rig_copy_rest_vertices(rig, rv, 3 * nv) == SKB_OK);
    CHECK(skb_rig_copy_posed_vertices(rig, pv, 3 * nv) == SKB_OK);
    CHECK(skb_rig_copy_skin_weights(rig, bi, w, 4 * nv) == SKB_OK);
    for (size_t v = 0; v < nv; ++v) {
        double acc[3] = {0, 0, 0}, wsum = 0;
        for (int k = 0; k < 4; ++k) {
            const uint32_t b = bi[4 * v + k];
            const double wt = w[4 * v + k];
            if (wt == 0.0) continue;
            CHECK(b < NB);
            if (b >= NB) continue;
            const quat inv = {-rest_gq[b].x, -rest_gq[b].y, -rest_gq[b].z, rest_gq[b].w};
            const double d[3] = {rv[3 * v] - rest_gt[b][0], rv[3 * v + 1] - rest_gt[b][1], rv[3 * v + 2] - rest_gt[b][2]};
            double local[3], moved[3];
            qrot(inv, d, local);
            qrot(posed_gq[b], local, moved);
            for (int c = 0; c < 3; ++c) acc[c] += wt * (posed_gt[b][c] + moved[c]);
            wsum += wt;
        }
        CHECK(fabs(wsum - 1.0) < 1e-3);
        const double got[3] = {pv[3 * v], pv[3 * v + 1], pv[3 * v + 2]};
        const double e = dist3(acc, got);
        if (e > *worst_skin) *worst_skin = e;
    }
    free(rv);
    free(pv);
    free(w);
    free(bi);

    /* Named errors. */
    char small[4];
    CHECK(skb_rig_copy_bone_name(rig, NB, names[0], 64) == SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_rig_copy_bone_name(rig, 1, small, strlen(names[1])) == SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(skb_rig_copy_local_rotations(rig, lr, 4 * NB - 1) == SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(skb_rig_copy_parents(rig, NULL, NB) == SKB_ERR_NULL_POINTER);
    skb_rig_free(rig);
}

int main(void) {
    struct skb_context *ctx = NULL;
    CHECK(skb_context_new(&ctx) == SKB_OK);
    struct skb_mesh *mesh = NULL;
    CHECK(skb_mesh_new_from_shape(ctx, SKB_GENDER_FEMALE, NULL, 0, &mesh) == SKB_OK);
    if (mesh == NULL) return 1;
    size_t nv = 0, nf = 0, nuv = 0;
    CHECK(skb_mesh_vertex_count(mesh, &nv) == SKB_OK && skb_mesh_face_count(mesh, &nf) == SKB_OK);
    double rest_joints[45], target[45];
    CHECK(skb_mesh_copy_joints(mesh, rest_joints, 45) == SKB_OK);

    /* Pose: the right forearm bent 70 degrees about the elbow (z axis), the left arm raised. */
    memcpy(target, rest_joints, sizeof target);
    const double a = 70.0 * 3.14159265358979 / 180.0;
    const double dx = rest_joints[12] - rest_joints[9], dy = rest_joints[13] - rest_joints[10];
    target[12] = rest_joints[9] + cos(a) * dx - sin(a) * dy;
    target[13] = rest_joints[10] + sin(a) * dx + cos(a) * dy;
    target[19] += 0.15;
    target[22] += 0.25;
    CHECK(skb_mesh_pose(mesh, target, 45, 0) == SKB_OK);
    double posed_joints[45];
    CHECK(skb_mesh_copy_posed_joints(mesh, posed_joints, 45) == SKB_OK);

    double worst_heads = 0, worst_skin = 0, worst_rest_joint = 0;
    int rigs = 0;
    for (uint32_t naming = 0; naming < 3; ++naming)
        for (uint32_t rest = 0; rest < 2; ++rest)
            for (uint32_t origin = 0; origin < 2; ++origin) {
                check_rig(mesh, naming, rest, origin, nv, rest_joints, posed_joints, &worst_heads, &worst_skin, &worst_rest_joint);
                ++rigs;
            }
    printf("capi_rig_test: %d rigs; importer vs library: posed heads max %.2e mm, skinned vertices max %.2e mm; "
           "joint-named rest heads on the joints max %.2e mm\n",
           rigs, 1e3 * worst_heads, 1e3 * worst_skin, 1e3 * worst_rest_joint);
    CHECK(worst_heads < 1e-4);
    CHECK(worst_skin < 1e-4);
    CHECK(worst_rest_joint < 1e-4);

    CHECK(named_joints == 2 * 14); /* 14 joint-named bones, 2 origins */
    printf("capi_rig_test: importer's posed joint-named bones vs skb_mesh_pose's joints max %.2e mm\n",
           1e3 * worst_posed_joint);
    CHECK(worst_posed_joint < 1e-4);

    struct skb_rig *rig = NULL;
    CHECK(skb_rig_new_from_mesh(mesh, NULL, &rig) == SKB_OK);
    CHECK(skb_rig_new_from_mesh(NULL, NULL, &rig) == SKB_ERR_NULL_POINTER);
    CHECK(skb_rig_new_from_mesh(mesh, NULL, NULL) == SKB_ERR_NULL_POINTER);
    skb_rig_free(rig);
    skb_rig_free(NULL);

    /* UVs and normals. */
    CHECK(skb_mesh_uv_count(mesh, &nuv) == SKB_OK && nuv > nv);
    float *uv = malloc(2 * nuv * sizeof *uv), *n = malloc(3 * nv * sizeof *n), *pn = malloc(3 * nv * sizeof *pn),
          *verts = malloc(3 * nv * sizeof *verts);
    uint32_t *fuv = malloc(4 * nf * sizeof *fuv), *faces = malloc(4 * nf * sizeof *faces),
             *tris = malloc(6 * nf * sizeof *tris);
    CHECK(skb_mesh_copy_uvs(mesh, uv, 2 * nuv) == SKB_OK);
    CHECK(skb_mesh_copy_face_uvs(mesh, fuv, 4 * nf) == SKB_OK);
    CHECK(skb_mesh_copy_faces(mesh, faces, 4 * nf) == SKB_OK);
    CHECK(skb_mesh_copy_triangles(mesh, tris, 6 * nf) == SKB_OK);
    CHECK(skb_mesh_copy_normals(mesh, false, n, 3 * nv) == SKB_OK);
    CHECK(skb_mesh_copy_normals(mesh, true, pn, 3 * nv) == SKB_OK);
    CHECK(skb_mesh_copy_vertices(mesh, verts, 3 * nv) == SKB_OK);
    CHECK(skb_mesh_copy_uvs(mesh, uv, 2 * nuv - 1) == SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(skb_mesh_copy_normals(NULL, false, n, 3 * nv) == SKB_ERR_NULL_POINTER);
    int uv_ok = 1, idx_ok = 1, unit_ok = 1;
    for (size_t i = 0; i < 2 * nuv; ++i) uv_ok &= uv[i] >= 0.0f && uv[i] <= 1.0f;
    for (size_t i = 0; i < 4 * nf; ++i) idx_ok &= fuv[i] < nuv && faces[i] < nv;
    for (size_t f = 0; f < nf; ++f) idx_ok &= tris[6 * f] == faces[4 * f] && tris[6 * f + 5] == faces[4 * f + 3];
    size_t moved = 0;
    double cx = 0, cz = 0;
    for (size_t v = 0; v < nv; ++v) {
        const double l = sqrt(n[3 * v] * n[3 * v] + n[3 * v + 1] * n[3 * v + 1] + n[3 * v + 2] * n[3 * v + 2]);
        unit_ok &= fabs(l - 1.0) < 1e-4;
        moved += fabs(n[3 * v] - pn[3 * v]) + fabs(n[3 * v + 1] - pn[3 * v + 1]) > 0.1;
        cx += verts[3 * v] / (double)nv;
        cz += verts[3 * v + 2] / (double)nv;
    }
    /* Outward: on the torso's side walls, normals point away from the body's vertical axis. */
    size_t outward = 0, side = 0;
    for (size_t v = 0; v < nv; ++v) {
        const double rx = verts[3 * v] - cx, rz = verts[3 * v + 2] - cz, y = verts[3 * v + 1];
        if (y < 0.0 || y > 0.4 || rx * rx + rz * rz > 0.04) continue;
        ++side;
        outward += rx * n[3 * v] + rz * n[3 * v + 2] > 0.0;
    }
    CHECK(uv_ok && idx_ok && unit_ok);
    CHECK(moved > 100);
    CHECK(side > 100 && outward * 10 > side * 9);
    printf("capi_rig_test: %zu UVs for %zu vertices; %zu of %zu torso normals outward; %zu normals turned by the pose\n",
           nuv, nv, outward, side, moved);
    free(uv);
    free(n);
    free(pn);
    free(verts);
    free(fuv);
    free(faces);
    free(tris);
    skb_mesh_free(mesh);
    skb_context_free(ctx);
    if (failures) fprintf(stderr, "capi_rig_test: %d failures\n", failures);
    return failures ? 1 : 0;
}
