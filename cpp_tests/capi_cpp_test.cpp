// Uses the C API through sketchbody.hpp (built -Wall -Wextra -Werror under ASan + UBSan):
// RAII results, exceptions carrying status and message, and thread-local error messages that
// do not leak between threads.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sketchbody.hpp"

static_assert(sizeof(skb_image) == 24, "skb_image layout is part of the ABI");
static_assert(sizeof(skb_status) == 4, "skb_status is 32 bits");

static int failures = 0;
#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (!(cond)) {                                                                \
            std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
            ++failures;                                                               \
        }                                                                             \
    } while (0)

struct Dummy {};
static int frees = 0;
static void free_dummy(Dummy *d) {
    if (d) {
        ++frees;
        delete d;
    }
}

template <typename F>
static skb_status status_of(F &&f) {
    try {
        f();
    } catch (const sketchbody::Error &e) {
        CHECK(std::string(e.what()).size() > 0);
        return e.status();
    }
    return SKB_OK;
}

int main() {
    CHECK(sketchbody::version() == SKB_VERSION_STRING);

    // A white square on black: Canny outlines it; every edge pixel lies on the square's border.
    const uint32_t n = 32;
    sketchbody::GrayImage img{n, n, std::vector<uint8_t>(n * n, 0)};
    for (uint32_t y = 8; y < 24; ++y)
        for (uint32_t x = 8; x < 24; ++x) img.pixels[y * n + x] = 255;
    sketchbody::GrayImage edges = sketchbody::canny(img.view(), 50, 150);
    size_t count = 0;
    for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x)
            if (edges.pixels[y * n + x]) {
                ++count;
                CHECK((x >= 7 && x <= 8) || (x >= 23 && x <= 24) || (y >= 7 && y <= 8) || (y >= 23 && y <= 24));
            }
    CHECK(count >= 60);

    // Errors become exceptions with the specific status.
    skb_image bad = img.view();
    bad.channels = 5;
    CHECK(status_of([&] { sketchbody::canny(bad, 1, 2); }) == SKB_ERR_UNSUPPORTED_CHANNELS);
    CHECK(status_of([&] { sketchbody::canny(img.view(), 1, 2, 9); }) == SKB_ERR_INVALID_APERTURE);
    CHECK(status_of([&] { sketchbody::canny(img.view(), NAN, 2); }) == SKB_ERR_NON_FINITE);
    CHECK(status_of([&] { sketchbody::gaussian_blur(img.view(), -1.0); }) == SKB_ERR_OUT_OF_RANGE);

    // Thread-local messages: an error on one thread leaves another thread's success clean.
    std::string other_thread_message = "not run";
    std::thread t([&] {
        sketchbody::canny(img.view(), 10, 20);
        other_thread_message = skb_last_error_message();
    });
    CHECK(status_of([&] { sketchbody::canny(bad, 1, 2); }) == SKB_ERR_UNSUPPORTED_CHANNELS);
    t.join();
    CHECK(other_thread_message.empty());
    CHECK(std::string(skb_last_error_message()).find("channel") != std::string::npos);

    // Handle<T, Free> is move-only and frees once (exercised with a counting deleter).
    using H = sketchbody::Handle<Dummy, free_dummy>;
    {
        H a(new Dummy);
        H b(std::move(a));
        CHECK(!a && b);
        H c;
        c = std::move(b);
    }
    CHECK(frees == 1);

    // The mesh and rig wrappers (issue 18): a posed mean body rigged with Mixamo names, T-pose
    // rest, origin on the floor.
    {
        sketchbody::Context ctx;
        sketchbody::Mesh mesh(ctx, SKB_GENDER_MALE);
        const size_t nv = mesh.vertex_count(), nf = mesh.face_count();
        std::vector<double> target = mesh.joints(false);
        target[3 * 4 + 1] += 0.3;  // right wrist raised
        mesh.pose(target);
        const std::vector<double> posed = mesh.joints(true);
        CHECK(posed[3 * 4 + 1] > target[3 * 4 + 1] - 0.3 + 0.1);  // the wrist went up (bone lengths kept)
        const std::vector<float> rest_n = mesh.normals(false), posed_n = mesh.normals(true);
        CHECK(rest_n.size() == 3 * nv && posed_n != rest_n);
        bool unit = true;
        for (size_t v = 0; v < nv; ++v)
            unit = unit && std::fabs(std::hypot(posed_n[3 * v], posed_n[3 * v + 1], posed_n[3 * v + 2]) - 1.0) < 1e-4;
        CHECK(unit);
        const std::vector<uint32_t> quads = mesh.faces(), tris = mesh.triangles(), fuv = mesh.face_uvs();
        const std::vector<float> uvs = mesh.uvs();
        CHECK(quads.size() == 4 * nf && tris.size() == 6 * nf && fuv.size() == 4 * nf && uvs.size() == 2 * mesh.uv_count());
        CHECK(tris[3] == quads[0] && tris[4] == quads[2] && tris[5] == quads[3]);
        bool in_range = true;
        for (uint32_t i : fuv) in_range = in_range && i < mesh.uv_count();
        CHECK(in_range);

        sketchbody::RigOptions o;
        o.naming = SKB_NAMING_MIXAMO;
        o.rest_pose = SKB_REST_T_POSE;
        const sketchbody::Rig rig = mesh.rig(o);
        const std::vector<std::string> names = rig.bone_names();
        const std::vector<int32_t> parents = rig.parents();
        CHECK(names.size() == SKB_NUM_RIG_BONES && names[0] == "mixamorig:Root" && names[1] == "mixamorig:Hips");
        CHECK(parents.size() == SKB_NUM_RIG_BONES && parents[0] == -1 && parents[1] == 0);
        CHECK(rig.rest_transforms().size() == SKB_RIG_TRANSFORM_LEN * SKB_NUM_RIG_BONES);
        const std::vector<double> lr = rig.local_rotations();
        bool unit_q = lr.size() == 4 * SKB_NUM_RIG_BONES;
        for (size_t b = 0; unit_q && b < SKB_NUM_RIG_BONES; ++b)
            unit_q = std::fabs(lr[4 * b] * lr[4 * b] + lr[4 * b + 1] * lr[4 * b + 1] + lr[4 * b + 2] * lr[4 * b + 2] +
                               lr[4 * b + 3] * lr[4 * b + 3] - 1.0) < 1e-9;
        CHECK(unit_q);
        const std::vector<float> pv = rig.posed_vertices(), rv = rig.rest_vertices();
        float low_posed = 1e9f, low_rest = 1e9f;
        for (size_t v = 0; v < nv; ++v) {
            low_posed = std::fmin(low_posed, pv[3 * v + 1]);
            low_rest = std::fmin(low_rest, rv[3 * v + 1]);
        }
        // Origin on the floor: the posed body stands on it; the T-pose rest (feet turned from the
        // A-pose the floor is measured on) within a centimetre.
        CHECK(std::fabs(low_posed) < 1e-5f && std::fabs(low_rest) < 0.01f);
        const sketchbody::SkinWeights skin = rig.skin_weights();
        bool bones_ok = skin.bones.size() == SKB_MAX_INFLUENCES * nv;
        for (uint32_t b : skin.bones) bones_ok = bones_ok && b < SKB_NUM_RIG_BONES;
        CHECK(bones_ok);
        CHECK(rig.posed_heads().size() == 3 * SKB_NUM_RIG_BONES && rig.root_translation().size() == 3);
        sketchbody::RigOptions bad;
        bad.naming = 7;
        CHECK(status_of([&] { mesh.rig(bad); }) == SKB_ERR_OUT_OF_RANGE);
        std::printf("capi_cpp_test: rig %zu bones (%s ... %s), %zu vertices, %zu UVs\n", names.size(), names[0].c_str(),
                    names.back().c_str(), nv, mesh.uv_count());

        // The texture: a green page seen from the front colours the texels facing it, the
        // others stay grey; written as PNG and read back by the library's colour decoder.
        const uint32_t w = 256, h = 512;
        std::vector<uint8_t> page(3 * w * h);
        for (size_t i = 0; i < page.size(); i += 3) page[i] = 10, page[i + 1] = 200, page[i + 2] = 30;
        const skb_image sketch{page.data(), w, h, 3 * w, 3};
        const skb_camera front{250, 250, {1, 0, 0, 0, 1, 0, 0, 0, 1}, {128, 470}};
        const sketchbody::Texture tex = mesh.texture(sketch, front, 128);
        size_t green = 0, grey = 0;
        for (size_t i = 0; i < tex.rgb.size(); i += 3) {
            green += tex.rgb[i] == 10 && tex.rgb[i + 1] == 200 && tex.rgb[i + 2] == 30;
            grey += tex.rgb[i] == 190 && tex.rgb[i + 1] == 190 && tex.rgb[i + 2] == 190;
        }
        CHECK(tex.size == 128 && tex.rgb.size() == 3 * 128 * 128 && green > 1000 && grey > 1000);
        const std::filesystem::path dir = std::filesystem::temp_directory_path() / "skb-capi-cpp-test";
        std::filesystem::create_directories(dir);
        const std::string png = (dir / "t.png").string();
        sketchbody::write_png(tex.view(), png);
        const sketchbody::LoadedColourImage back(png);
        const skb_image bv = back.view();
        CHECK(bv.width == 128 && bv.channels == 3 && std::equal(tex.rgb.begin(), tex.rgb.end(), bv.data));
        CHECK(status_of([&] { mesh.texture(sketch, front, 0); }) == SKB_ERR_OUT_OF_RANGE);
        // FBX and USD in centimetres, Z up.
        sketchbody::RigOptions cm_z;
        cm_z.units = SKB_UNITS_CENTIMETRES;
        cm_z.up_axis = SKB_UP_Z;
        const std::string usd = (dir / "b.usda").string(), fbx = (dir / "b.fbx").string();
        mesh.write_usd(usd, cm_z);
        mesh.write_fbx(fbx, cm_z);
        std::stringstream text;
        text << std::ifstream(usd).rdbuf();
        CHECK(text.str().find("metersPerUnit = 0.01\n") != std::string::npos);
        CHECK(text.str().find("upAxis = \"Z\"\n") != std::string::npos);
        CHECK(std::filesystem::file_size(fbx) > 100000);
        sketchbody::RigOptions bad_units;
        bad_units.units = 9;
        CHECK(status_of([&] { mesh.write_usd(usd, bad_units); }) == SKB_ERR_OUT_OF_RANGE);
        std::filesystem::remove_all(dir);
        std::printf("capi_cpp_test: texture %zu green / %zu grey texels of 128x128; FBX, USD in cm, Z up\n", green, grey);
    }

    {
        // The main job with interim bodies: the posed mean shape, then the deciding fit, then a
        // result equal to run_pipeline's; per-part support in 0..1 or NaN.
        sketchbody::Context ctx;
        const sketchbody::LoadedColourImage sketch(SKB_SOURCE_DIR "/assets/examples/sketch.png");
        skb_joints2d joints{};
        sketchbody::check(skb_joints2d_read_json(SKB_SOURCE_DIR "/assets/examples/sketch_joints.json", &joints));
        sketchbody::FitOptions fit;
        fit.samples(24).iterations(2);
        std::vector<uint32_t> stages;
        std::vector<float> first;
        const sketchbody::Result r = sketchbody::run_pipeline_progressive(
            ctx, sketch.view(), &joints, &fit, [&](uint32_t stage, const std::vector<float> &v) {
                stages.push_back(stage);
                if (first.empty()) first = v;
            });
        const sketchbody::Result plain = sketchbody::run_pipeline(ctx, sketch.view(), &joints, &fit);
        CHECK((stages == std::vector<uint32_t>{SKB_INTERIM_MEAN_SHAPE, SKB_INTERIM_DECIDING_FIT}));
        CHECK(r.vertices(true) == plain.vertices(true));
        CHECK(first.size() == 3 * r.vertex_count() && first != r.vertices(true));
        const std::vector<double> parts = r.part_support();
        CHECK(parts.size() == SKB_NUM_BODY_PARTS && std::isfinite(parts[1]));
        for (double p : parts) CHECK(std::isnan(p) || (p >= 0 && p <= 1));
        // An exception in the interim callback cancels the run.
        CHECK(status_of([&] {
                  sketchbody::run_pipeline_progressive(ctx, sketch.view(), &joints, &fit,
                                                       [](uint32_t, const std::vector<float> &) { throw 1; });
              }) == SKB_ERR_CANCELLED);
        std::printf("capi_cpp_test: progressive run, %zu interim bodies; torso support %.2f\n", stages.size(), parts[1]);
    }

    {
        // A turnaround: the same body and pose rendered from the front and the side (yaw +90°),
        // fitted as one body; the side view reads back with its label and the front camera turned
        // by +90°; the side view labelled as the other side is refused (drawn facing the other way).
        sketchbody::Context ctx;
        skb_sketch_options *so = nullptr;
        sketchbody::check(skb_sketch_options_new(&so));
        const uint32_t size = 256;
        std::vector<uint8_t> front(size * size), side(size * size);
        double fxy[30], sxy[30];
        uint8_t fvis[15], svis[15];
        sketchbody::check(skb_sketch_options_set_camera(so, 0, 0, 0));
        sketchbody::check(skb_context_render_sketch(ctx.get(), SKB_GENDER_FEMALE, nullptr, 0, nullptr, 11, size, size, so,
                                            front.data(), size, front.size(), fxy, fvis));
        sketchbody::check(skb_sketch_options_set_camera(so, 90, 0, 0));
        sketchbody::check(skb_context_render_sketch(ctx.get(), SKB_GENDER_FEMALE, nullptr, 0, nullptr, 11, size, size, so,
                                            side.data(), size, side.size(), sxy, svis));
        skb_sketch_options_free(so);
        skb_joints2d fj{}, sj{};
        for (int k = 0; k < 15; ++k) {
            fj.xy[k][0] = fxy[2 * k], fj.xy[k][1] = fxy[2 * k + 1], fj.visible[k] = 1;
            sj.xy[k][0] = sxy[2 * k], sj.xy[k][1] = sxy[2 * k + 1], sj.visible[k] = 1;
        }
        const skb_image fi{front.data(), size, size, size, 1}, si{side.data(), size, size, size, 1};
        sketchbody::FitOptions fit;
        fit.samples(24).iterations(2);
        const sketchbody::Result r = sketchbody::run_pipeline_views(ctx, fi, &fj, {{SKB_VIEW_SIDE, si, &sj}}, &fit);
        const std::vector<skb_view_info> views = r.views();
        CHECK(views.size() == 1 && views[0].label == SKB_VIEW_SIDE && views[0].joints_detected == 0);
        const skb_camera c = r.camera();
        // R_front^T R_side turns by 90° about the body's (tilted) vertical axis.
        double rel[9] = {0};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                for (int k = 0; k < 3; ++k) rel[3 * i + j] += c.r[3 * k + i] * views[0].camera.r[3 * k + j];
        const double cos_angle = (rel[0] + rel[4] + rel[8] - 1) / 2;  // cos 90° = 0
        const double ax = rel[7] - rel[5], ay = rel[2] - rel[6], az = rel[3] - rel[1];
        CHECK(std::fabs(cos_angle) < 1e-9 && ay / std::sqrt(ax * ax + ay * ay + az * az) > 0.9);
        CHECK(views[0].residual < 0.05 && views[0].edge_support > 0.3);
        CHECK(sketchbody::run_pipeline(ctx, fi, &fj, &fit).views().empty());
        CHECK(status_of([&] {
                  sketchbody::run_pipeline_views(ctx, fi, &fj, {{SKB_VIEW_SIDE_LEFT, si, &sj}}, &fit);
              }) == SKB_ERR_VIEWS_DISAGREE);
        std::printf("capi_cpp_test: turnaround front + side, side residual %.3f, support %.2f\n", views[0].residual,
                    views[0].edge_support);
    }

    std::printf("%s (%d failed checks)\n", failures ? "FAIL" : "PASS", failures);
    return failures ? 1 : 0;
}
