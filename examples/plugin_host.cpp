// plugin_host: behaves like a DCC plug-in using sketchbody through sketchbody.hpp. It loads a
// sketch with the library's decoder, reads the sketch's 2-D joints (sketchbody-joints2d JSON),
// runs the main job, takes the vertices, faces, joints and skin weights a host would turn into a
// rigged mesh, checks them, exercises cancellation and the detector (no joints given), and frees
// everything (RAII). Built and run by ctest under ASan + UBSan (cpp_tests/CMakeLists.txt):
//   plugin_host SKETCH.png JOINTS.json
#include <sketchbody.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace {

int failures = 0;

void expect(bool ok, const char *what) {
    if (!ok) {
        std::fprintf(stderr, "FAIL: %s\n", what);
        ++failures;
    }
}

const char *kJointNames[15] = {"head", "neck", "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist",
                               "pelvis", "r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle"};

// Reads the "joints" of a sketchbody-joints2d file: for each name, the two numbers of the array
// after "name". Enough JSON for the files sketchbody writes; a host would use its JSON library.
bool read_joints(const std::string &path, skb_joints2d &out) {
    std::ifstream f(path);
    if (!f) return false;
    std::stringstream ss;
    ss << f.rdbuf();
    const std::string text = ss.str();
    out = skb_joints2d{};
    for (int j = 0; j < 15; ++j) {
        const std::string key = std::string("\"") + kJointNames[j] + "\"";
        size_t at = text.find(key);
        if (at == std::string::npos) return false;
        at = text.find('[', at);
        if (at == std::string::npos) return false;
        char *end = nullptr;
        out.xy[j][0] = std::strtod(text.c_str() + at + 1, &end);
        const char *comma = std::strchr(end, ',');
        if (comma == nullptr) return false;
        out.xy[j][1] = std::strtod(comma + 1, &end);
        out.visible[j] = 1;
    }
    return true;
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: plugin_host SKETCH.png JOINTS.json\n");
        return 2;
    }
    try {
        sketchbody::LoadedImage sketch(argv[1]);
        skb_joints2d joints{};
        if (!read_joints(argv[2], joints)) {
            std::fprintf(stderr, "plugin_host: cannot read joints from %s\n", argv[2]);
            return 2;
        }
        sketchbody::Context ctx;
        sketchbody::FitOptions fit;
        fit.samples(24).iterations(2).seed(7);  // quick settings: the host checks plumbing

        float last = -1.0f;
        bool monotone = true;
        sketchbody::Result r = sketchbody::run_pipeline(ctx, sketch.view(), &joints, &fit, [&](float f) {
            monotone = monotone && f >= last;
            last = f;
            return true;
        });
        expect(monotone && last == 1.0f, "progress rises to 1");

        const size_t nv = r.vertex_count(), nf = r.face_count();
        expect(nv == 13380 && nf == 13378, "MakeHuman body: 13380 vertices, 13378 faces");
        const std::vector<float> posed = r.vertices(true), rest = r.vertices(false);
        const std::vector<uint32_t> faces = r.faces();
        bool finite = true;
        float ylo = 1e9f, yhi = -1e9f;
        for (size_t i = 0; i < posed.size(); ++i) finite = finite && std::isfinite(posed[i]) && std::isfinite(rest[i]);
        for (size_t v = 0; v < nv; ++v) {
            ylo = std::fmin(ylo, rest[3 * v + 1]);
            yhi = std::fmax(yhi, rest[3 * v + 1]);
        }
        expect(finite, "vertices are finite");
        expect(yhi - ylo > 1.3f && yhi - ylo < 2.2f, "rest height is a person's");
        bool in_range = true;
        for (uint32_t i : faces) in_range = in_range && i < nv;
        expect(in_range, "face indices are in range");

        const skb_joints2d used = r.joints2d();
        bool same = true;
        for (int j = 0; j < 15; ++j) same = same && used.xy[j][0] == joints.xy[j][0] && used.xy[j][1] == joints.xy[j][1];
        expect(same, "the result keeps the given 2-D joints");
        const std::vector<double> pj = r.joints3d(SKB_JOINTS_POSED), ej = r.joints3d(SKB_JOINTS_ESTIMATED);
        bool jf = true;
        for (size_t k = 0; k < pj.size(); ++k) jf = jf && std::isfinite(pj[k]) && std::isfinite(ej[k]);
        expect(jf, "3-D joints are finite");
        // The posed mesh's pelvis sits on the estimated pelvis (the IK root).
        expect(std::fabs(pj[3 * 8] - ej[3 * 8]) < 1e-6 && std::fabs(pj[3 * 8 + 1] - ej[3 * 8 + 1]) < 1e-6, "pelvis on the estimate");
        // The result's camera is the posed body's: it projects the posed head near the given
        // head joint (the estimated joints are at the pose step's 1.75 m scale).
        const skb_camera cam = r.camera();
        const double hx = cam.sx * (cam.r[0] * pj[0] + cam.r[1] * pj[1] + cam.r[2] * pj[2]) + cam.t[0];
        const double hy = -cam.sy * (cam.r[3] * pj[0] + cam.r[4] * pj[1] + cam.r[5] * pj[2]) + cam.t[1];
        expect(std::hypot(hx - joints.xy[0][0], hy - joints.xy[0][1]) < 25.0, "camera reprojects the posed head");

        const sketchbody::SkinWeights skin = r.skin_weights();
        bool weights_ok = true;
        for (size_t v = 0; v < nv; ++v) {
            float sum = 0;
            for (int k = 0; k < 4; ++k) {
                weights_ok = weights_ok && skin.bones[4 * v + k] < SKB_NUM_BONES && skin.weights[4 * v + k] >= 0.0f;
                sum += skin.weights[4 * v + k];
            }
            weights_ok = weights_ok && std::fabs(sum - 1.0f) < 1e-3f;
        }
        expect(weights_ok, "skin weights: bones 0..13, non-negative, summing to 1");
        expect(!r.shape_weights().empty(), "shape weights present");
        const uint32_t g = r.gender();
        expect(r.gender_by_score() && (g == SKB_GENDER_FEMALE || g == SKB_GENDER_MALE), "gender fitted");
        const double gv = r.gender_value(), gc = r.gender_confidence();
        expect(gv >= 0.0 && gv <= 1.0 && gc >= 0.5 && gc <= 1.0 && (g == SKB_GENDER_MALE) == (gv > 0.5),
               "gender value in 0..1, confidence in 0.5..1, gender its nearer end");
        expect(std::isfinite(r.score(g)), "the fit's score");

        // Re-posing the fitted body without re-fitting its shape: a limb's depth flipped there
        // and back, a depth reading picked, moved joints, and a joint dragged off the sketch.
        expect(r.alternative_count() >= 2, "the pose lists depth readings");
        uint32_t flipped = SKB_NUM_LIMBS;
        for (uint32_t l = 0; l < SKB_NUM_LIMBS && flipped == SKB_NUM_LIMBS; ++l)
            if (r.flip_limb(l) == SKB_REPOSE_DONE) flipped = l;
        const std::vector<float> flipped_posed = r.vertices(true);
        expect(flipped < SKB_NUM_LIMBS && flipped_posed != posed && r.vertices(false) == rest,
               "a flipped limb re-poses the body, its rest shape kept");
        expect(r.flip_limb(flipped) == SKB_REPOSE_DONE && r.pick_alternative(1) == SKB_REPOSE_DONE,
               "flip back, pick a reading");
        skb_joints2d moved = joints;
        moved.xy[4][0] -= 20.0;
        expect(r.repose(moved) == SKB_REPOSE_DONE && r.vertices(false) == rest, "moved joints re-pose the body");
        moved.xy[4][0] = -50.0;
        const std::vector<float> before_off = r.vertices(true);
        expect(r.repose(moved) == SKB_REPOSE_JOINT_OUTSIDE_IMAGE && r.vertices(true) == before_off,
               "a joint off the sketch changes nothing");

        // Cancellation: the first fit progress report cancels; the call returns promptly.
        sketchbody::FitOptions slow;
        slow.samples(200).iterations(100).gender(SKB_GENDER_MALE);
        const auto t0 = std::chrono::steady_clock::now();
        try {
            sketchbody::run_pipeline(ctx, sketch.view(), &joints, &slow, [](float f) { return f <= 0.06f; });
            expect(false, "a cancelled run throws");
        } catch (const sketchbody::Error &e) {
            expect(e.status() == SKB_ERR_CANCELLED, "cancel gives SKB_ERR_CANCELLED");
        }
        const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

        // No joints: the embedded detector finds them near the drawn ones.
        sketchbody::Result d = sketchbody::run_pipeline(ctx, sketch.view(), nullptr, &fit);
        const skb_joints2d found = d.joints2d();
        double ymin = 1e9, ymax = -1e9;
        for (int j = 0; j < 15; ++j) {
            ymin = std::fmin(ymin, joints.xy[j][1]);
            ymax = std::fmax(ymax, joints.xy[j][1]);
        }
        int visible = 0, close = 0;
        for (int j = 0; j < 15; ++j) {
            if (!found.visible[j]) continue;
            ++visible;
            close += std::hypot(found.xy[j][0] - joints.xy[j][0], found.xy[j][1] - joints.xy[j][1]) < 0.2 * (ymax - ymin);
        }
        expect(visible >= 12 && 5 * close >= 4 * visible, "most detected joints within 0.2 figure heights of the drawn ones");
        expect(d.vertex_count() == 13380, "the detected-joints run gives a body");
        std::printf("plugin_host: %zu vertices, %zu faces, gender %s (value %.4f, confidence %.4f), cancel in %.2f s\n", nv,
                    nf, g == SKB_GENDER_FEMALE ? "female" : "male", gv, gc, secs);
    } catch (const sketchbody::Error &e) {
        std::fprintf(stderr, "plugin_host: sketchbody error %d: %s\n", static_cast<int>(e.status()), e.what());
        return 1;
    }
    if (failures > 0) return 1;
    std::printf("plugin_host: OK\n");
    return 0;
}
