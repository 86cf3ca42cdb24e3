// sketchbody.hpp: header-only C++17 RAII wrapper over the sketchbody C API (sketchbody.h).
// Errors become sketchbody::Error exceptions carrying the status and the library's message.
// Handles are move-only and free themselves. Thread-safety is that of the wrapped C objects.
#ifndef SKETCHBODY_HPP
#define SKETCHBODY_HPP

#include <cstddef>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sketchbody.h"

namespace sketchbody {

/// A failed sketchbody call: status() is the skb_status code, what() the specific message.
class Error : public std::runtime_error {
public:
    Error(skb_status status, const std::string &message) : std::runtime_error(message), status_(status) {}
    skb_status status() const noexcept { return status_; }

private:
    skb_status status_;
};

/// Throws Error for any status other than SKB_OK.
inline void check(skb_status status) {
    if (status != SKB_OK) {
        std::string message = skb_last_error_message();
        if (message.empty()) message = skb_status_str(status);
        throw Error(status, message);
    }
}

/// Version of the loaded library ("MAJOR.MINOR.PATCH"); compare with SKB_VERSION_STRING.
inline std::string version() { return skb_version(); }

/// Owns a C handle T* released with Free (NULL-safe). Move-only.
template <typename T, void (*Free)(T *)>
class Handle {
public:
    Handle() = default;
    explicit Handle(T *raw) noexcept : raw_(raw) {}
    Handle(const Handle &) = delete;
    Handle &operator=(const Handle &) = delete;
    Handle(Handle &&other) noexcept : raw_(std::exchange(other.raw_, nullptr)) {}
    Handle &operator=(Handle &&other) noexcept {
        if (this != &other) {
            Free(raw_);
            raw_ = std::exchange(other.raw_, nullptr);
        }
        return *this;
    }
    ~Handle() { Free(raw_); }
    T *get() const noexcept { return raw_; }
    T **out() noexcept {  // for C functions that create into T** (frees any current value)
        Free(raw_);
        raw_ = nullptr;
        return &raw_;
    }
    explicit operator bool() const noexcept { return raw_ != nullptr; }

private:
    T *raw_ = nullptr;
};

/// An owned, tightly packed 8-bit gray image.
struct GrayImage {
    uint32_t width = 0;
    uint32_t height = 0;
    std::vector<uint8_t> pixels;  // width * height bytes, row-major

    /// A borrowed skb_image view of this image (valid while the image lives).
    skb_image view() const noexcept { return skb_image{pixels.data(), width, height, width, 1}; }
};

/// Canny edges (255 edge / 0), bit-exact with OpenCV's cv::Canny; see skb_image_canny.
inline GrayImage canny(const skb_image &src, double threshold1, double threshold2, int aperture = 3,
                       bool l2_gradient = false) {
    GrayImage out{src.width, src.height, std::vector<uint8_t>(size_t(src.width) * src.height)};
    check(skb_image_canny(&src, threshold1, threshold2, aperture, l2_gradient, out.pixels.data(), src.width,
                    out.pixels.size()));
    return out;
}

/// Gaussian blur of a gray image, compatible with cv::GaussianBlur(Size(0,0), sigma).
inline GrayImage gaussian_blur(const skb_image &src, double sigma) {
    GrayImage out{src.width, src.height, std::vector<uint8_t>(size_t(src.width) * src.height)};
    check(skb_image_gaussian_blur(&src, sigma, out.pixels.data(), src.width, out.pixels.size()));
    return out;
}

/// A decoded image file (PNG/JPEG) as 8-bit gray; see skb_gray_image_new_from_file.
class LoadedImage {
public:
    explicit LoadedImage(const std::string &path) { check(skb_gray_image_new_from_file(path.c_str(), img_.out())); }
    /// A borrowed view, valid while this object lives.
    skb_image view() const {
        skb_image v{};
        check(skb_gray_image_view(img_.get(), &v));
        return v;
    }

private:
    Handle<skb_gray_image, skb_gray_image_free> img_;
};

/// A decoded image file (PNG/JPEG) as 8-bit RGB, transparency over white: the sketch as
/// `sketchbody run` reads it for the texture; see skb_rgb_image_new_from_file.
class LoadedColourImage {
public:
    explicit LoadedColourImage(const std::string &path) { check(skb_rgb_image_new_from_file(path.c_str(), img_.out())); }
    /// A borrowed 3-channel view, valid while this object lives.
    skb_image view() const {
        skb_image v{};
        check(skb_rgb_image_view(img_.get(), &v));
        return v;
    }

private:
    Handle<skb_rgb_image, skb_rgb_image_free> img_;
};

/// Writes an 8-bit PNG (1, 3 or 4 channels) with the library's encoder, atomically; see
/// skb_image_write_png.
inline void write_png(const skb_image &img, const std::string &path) { check(skb_image_write_png(&img, path.c_str())); }

/// An RGB texture, `size` × `size` texels, 3 bytes each, rows packed, row 0 at v = 1.
struct Texture {
    uint32_t size = 0;
    std::vector<uint8_t> rgb;
    /// A borrowed view for write_png, valid while this object lives.
    skb_image view() const { return skb_image{rgb.data(), size, size, 3 * size, 3}; }
};

/// The library context (holds the body model); shareable across threads.
class Context {
public:
    Context() { check(skb_context_new(ctx_.out())); }
    const skb_context *get() const noexcept { return ctx_.get(); }

private:
    Handle<skb_context, skb_context_free> ctx_;
};

/// Shape-fit options (defaults as documented in sketchbody.h); setters throw Error on bad values.
class FitOptions {
public:
    FitOptions() { check(skb_fit_options_new(o_.out())); }
    FitOptions &samples(uint32_t v) { check(skb_fit_options_set_samples(o_.get(), v)); return *this; }
    FitOptions &iterations(uint32_t v) { check(skb_fit_options_set_iterations(o_.get(), v)); return *this; }
    FitOptions &transition_scale(double v) { check(skb_fit_options_set_transition_scale(o_.get(), v)); return *this; }
    FitOptions &score(uint32_t v) { check(skb_fit_options_set_score(o_.get(), v)); return *this; }
    FitOptions &temperature(double v) { check(skb_fit_options_set_temperature(o_.get(), v)); return *this; }
    FitOptions &raster_side(uint32_t v) { check(skb_fit_options_set_raster_side(o_.get(), v)); return *this; }
    FitOptions &tolerance(double v) { check(skb_fit_options_set_tolerance(o_.get(), v)); return *this; }
    FitOptions &seed(uint64_t v) { check(skb_fit_options_set_seed(o_.get(), v)); return *this; }
    FitOptions &skinning(uint32_t v) { check(skb_fit_options_set_skinning(o_.get(), v)); return *this; }
    FitOptions &dims(uint32_t v) { check(skb_fit_options_set_dims(o_.get(), v)); return *this; }
    FitOptions &gender(uint32_t v) { check(skb_fit_options_set_gender(o_.get(), v)); return *this; }
    /// The character's known rest height in metres (0 = unknown).
    FitOptions &height(double metres) { check(skb_fit_options_set_height(o_.get(), metres)); return *this; }
    FitOptions &sample_camera(bool on) { check(skb_fit_options_set_sample_camera(o_.get(), on)); return *this; }
    FitOptions &proportion_sd(double v) { check(skb_fit_options_set_proportion_sd(o_.get(), v)); return *this; }
    /// Centre the bone factors' prior on their estimate from the 2-D bone lengths (default on).
    FitOptions &estimate_proportions(bool on) { check(skb_fit_options_set_estimate_proportions(o_.get(), on)); return *this; }
    const skb_fit_options *get() const noexcept { return o_.get(); }

private:
    Handle<skb_fit_options, skb_fit_options_free> o_;
};

/// Progress callback for run_pipeline: return false to cancel (the call then throws Error with
/// status SKB_ERR_CANCELLED).
using Progress = std::function<bool(float)>;

namespace detail {
inline int progress_trampoline(void *user, float fraction) {
    auto *p = static_cast<Progress *>(user);
    try {
        return (*p)(fraction) ? 0 : 1;
    } catch (...) {
        return 1;  // an exception in the callback cancels the run
    }
}
}  // namespace detail

/// Skin weights of a mesh: for vertex v, bones[4v..4v+3] (bone indices 0..13) and weights.
struct SkinWeights {
    std::vector<uint32_t> bones;
    std::vector<float> weights;
};

namespace detail {
/// n elements copied out by a C getter f(handle, dst, dst_len).
template <typename T, typename F, typename H>
std::vector<T> copy_out(F f, const H *handle, size_t n) {
    std::vector<T> v(n);
    check(f(handle, v.data(), v.size()));
    return v;
}
}  // namespace detail

/// Options of the production rig (skb_export_options): bone names, rest pose, origin, twist
/// bones, how the pose is carried, IK targets; the FBX and USD files' unit and up axis (the GLB
/// and the in-memory rig stay metres, Y up).
struct RigOptions {
    uint32_t naming = SKB_NAMING_PROJECT;     // SKB_NAMING_*
    uint32_t rest_pose = SKB_REST_A_POSE;     // SKB_REST_*
    uint32_t origin = SKB_ORIGIN_FLOOR;       // SKB_ORIGIN_*
    uint32_t units = SKB_UNITS_METRES;        // SKB_UNITS_* (FBX, USD)
    uint32_t up_axis = SKB_UP_Y;              // SKB_UP_* (FBX, USD)
    bool twist_bones = false;                 // + SKB_NUM_TWIST_BONES twist bones
    uint32_t pose_as = SKB_POSE_AS_ACTION;    // SKB_POSE_AS_*
    bool ik_targets = false;                  // + SKB_NUM_IK_BONES IK target bones
};

namespace detail {
/// An skb_export_options handle holding `o` (throws Error on a value out of range).
inline Handle<skb_export_options, skb_export_options_free> export_options(const RigOptions &o) {
    Handle<skb_export_options, skb_export_options_free> h;
    check(skb_export_options_new(h.out()));
    check(skb_export_options_set_naming(h.get(), o.naming));
    check(skb_export_options_set_rest_pose(h.get(), o.rest_pose));
    check(skb_export_options_set_origin(h.get(), o.origin));
    check(skb_export_options_set_units(h.get(), o.units));
    check(skb_export_options_set_up_axis(h.get(), o.up_axis));
    check(skb_export_options_set_twist_bones(h.get(), o.twist_bones));
    check(skb_export_options_set_pose_as(h.get(), o.pose_as));
    check(skb_export_options_set_ik_targets(h.get(), o.ik_targets));
    return h;
}
}  // namespace detail

/// The production rig of a mesh as the rigged GLB writes it (see skb_rig_*). Move-only.
class Rig {
public:
    explicit Rig(skb_rig *raw) noexcept : r_(raw) {}
    size_t bone_count() const { size_t n = 0; check(skb_rig_bone_count(r_.get(), &n)); return n; }
    size_t vertex_count() const { size_t n = 0; check(skb_rig_vertex_count(r_.get(), &n)); return n; }
    /// Bone names in the chosen convention, in the GLB's node order.
    std::vector<std::string> bone_names() const {
        std::vector<std::string> names(bone_count());
        for (size_t b = 0; b < names.size(); ++b) {
            size_t n = 0;
            check(skb_rig_bone_name_length(r_.get(), b, &n));
            std::string s(n + 1, '\0');
            check(skb_rig_copy_bone_name(r_.get(), b, &s[0], s.size()));
            s.resize(n);
            names[b] = s;
        }
        return names;
    }
    /// Parent index per bone, -1 for the root; parents come first.
    std::vector<int32_t> parents() const { return copy<int32_t>(skb_rig_copy_parents, bone_count()); }
    /// SKB_RIG_TRANSFORM_LEN doubles per bone: rest translation x, y, z (parent bone frame) and
    /// rotation quaternion x, y, z, w, relative to the parent.
    std::vector<double> rest_transforms() const {
        return copy<double>(skb_rig_copy_rest_transforms, SKB_RIG_TRANSFORM_LEN * bone_count());
    }
    /// 4 doubles per bone: the posed rotation relative to the parent (x, y, z, w).
    std::vector<double> local_rotations() const { return copy<double>(skb_rig_copy_local_rotations, 4 * bone_count()); }
    /// The root's translation in the pose, metres.
    std::vector<double> root_translation() const { return copy<double>(skb_rig_copy_root_translation, 3); }
    /// Model frame -> export frame translation, metres.
    std::vector<double> offset() const { return copy<double>(skb_rig_copy_offset, 3); }
    /// Posed bone heads (x, y, z per bone), metres, as the library computes them.
    std::vector<double> posed_heads() const { return copy<double>(skb_rig_copy_posed_heads, 3 * bone_count()); }
    /// The bind-pose vertices (x, y, z per vertex), metres.
    std::vector<float> rest_vertices() const { return copy<float>(skb_rig_copy_rest_vertices, 3 * vertex_count()); }
    /// The rig's own skinning of them in the pose, metres.
    std::vector<float> posed_vertices() const { return copy<float>(skb_rig_copy_posed_vertices, 3 * vertex_count()); }
    /// Skin weights to the rig's bones (SKB_MAX_INFLUENCES slots per vertex).
    SkinWeights skin_weights() const {
        SkinWeights s{std::vector<uint32_t>(SKB_MAX_INFLUENCES * vertex_count()), std::vector<float>(SKB_MAX_INFLUENCES * vertex_count())};
        check(skb_rig_copy_skin_weights(r_.get(), s.bones.data(), s.weights.data(), s.bones.size()));
        return s;
    }
    const skb_rig *get() const noexcept { return r_.get(); }

private:
    template <typename T, typename F>
    std::vector<T> copy(F f, size_t n) const { return detail::copy_out<T>(f, r_.get(), n); }
    Handle<skb_rig, skb_rig_free> r_;
};

/// An owned body mesh (see skb_mesh_*). Move-only.
class Mesh {
public:
    explicit Mesh(skb_mesh *raw) noexcept : m_(raw) {}
    /// The rest-pose mesh of `gender` with PCA `weights` (empty: the mean shape).
    Mesh(const Context &ctx, uint32_t gender, const std::vector<float> &weights = {}) {
        check(skb_mesh_new_from_shape(ctx.get(), gender, weights.empty() ? nullptr : weights.data(), weights.size(), m_.out()));
    }
    size_t vertex_count() const { size_t n = 0; check(skb_mesh_vertex_count(m_.get(), &n)); return n; }
    size_t face_count() const { size_t n = 0; check(skb_mesh_face_count(m_.get(), &n)); return n; }
    size_t uv_count() const { size_t n = 0; check(skb_mesh_uv_count(m_.get(), &n)); return n; }
    /// x, y, z per vertex, metres: the current pose's or the rest's.
    std::vector<float> vertices(bool posed) const {
        std::vector<float> v(3 * vertex_count());
        check(posed ? skb_mesh_copy_posed_vertices(m_.get(), v.data(), v.size()) : skb_mesh_copy_vertices(m_.get(), v.data(), v.size()));
        return v;
    }
    /// Unit vertex normals (x, y, z per vertex) of the posed or rest vertices.
    std::vector<float> normals(bool posed) const {
        std::vector<float> n(3 * vertex_count());
        check(skb_mesh_copy_normals(m_.get(), posed, n.data(), n.size()));
        return n;
    }
    /// 4 vertex indices per quad face.
    std::vector<uint32_t> faces() const { return copy<uint32_t>(skb_mesh_copy_faces, 4 * face_count()); }
    /// 3 vertex indices per triangle, two triangles per quad.
    std::vector<uint32_t> triangles() const { return copy<uint32_t>(skb_mesh_copy_triangles, 6 * face_count()); }
    /// u, v per UV coordinate (v up).
    std::vector<float> uvs() const { return copy<float>(skb_mesh_copy_uvs, 2 * uv_count()); }
    /// 4 UV indices per quad face, in the corner order of faces().
    std::vector<uint32_t> face_uvs() const { return copy<uint32_t>(skb_mesh_copy_face_uvs, 4 * face_count()); }
    /// The 15 joints (45 doubles), metres: posed or rest.
    std::vector<double> joints(bool posed) const {
        std::vector<double> j(3 * SKB_NUM_JOINTS);
        check(posed ? skb_mesh_copy_posed_joints(m_.get(), j.data(), j.size()) : skb_mesh_copy_joints(m_.get(), j.data(), j.size()));
        return j;
    }
    /// Poses the mesh to 15 target joints (45 doubles), see skb_mesh_pose.
    void pose(const std::vector<double> &joints, uint32_t flags = 0) {
        check(skb_mesh_pose(m_.get(), joints.data(), joints.size(), flags));
    }
    /// The production rig in the current pose, for `options`.
    Rig rig(const RigOptions &options = {}) const {
        auto o = detail::export_options(options);
        skb_rig *raw = nullptr;
        check(skb_rig_new_from_mesh(m_.get(), o.get(), &raw));
        return Rig(raw);
    }
    /// Binary FBX 7.4 of the rigged, posed body in the options' unit and up axis; skb_mesh_write_fbx.
    void write_fbx(const std::string &path, const RigOptions &options = {}) const {
        auto o = detail::export_options(options);
        check(skb_mesh_write_fbx(m_.get(), path.c_str(), o.get()));
    }
    /// UsdSkel .usda of the rigged, posed body in the options' unit and up axis; skb_mesh_write_usd.
    void write_usd(const std::string &path, const RigOptions &options = {}) const {
        auto o = detail::export_options(options);
        check(skb_mesh_write_usd(m_.get(), path.c_str(), o.get()));
    }
    /// The sketch seen through `cam` projected onto the mesh in its current pose, into the UV
    /// layout; skb_mesh_project_texture.
    Texture texture(const skb_image &sketch, const skb_camera &cam, uint32_t size = SKB_DEFAULT_TEXTURE_SIZE) const {
        Texture t{size, std::vector<uint8_t>(3 * size_t(size) * size)};
        check(skb_mesh_project_texture(m_.get(), &sketch, &cam, size, t.rgb.data(), 3 * size_t(size), t.rgb.size(),
                                       nullptr, nullptr));
        return t;
    }
    const skb_mesh *get() const noexcept { return m_.get(); }

private:
    template <typename T, typename F>
    std::vector<T> copy(F f, size_t n) const { return detail::copy_out<T>(f, m_.get(), n); }
    Handle<skb_mesh, skb_mesh_free> m_;
};

/// The owned result of run_pipeline (see skb_result_*). Move-only.
class Result {
public:
    explicit Result(skb_result *raw) noexcept : r_(raw) {}
    uint32_t gender() const { uint32_t g = 0; check(skb_result_gender(r_.get(), &g, nullptr)); return g; }
    /// True when the gender was fitted (automatic), false when given.
    bool gender_by_score() const { uint32_t g = 0; bool b = false; check(skb_result_gender(r_.get(), &g, &b)); return b; }
    /// Fitted gender value, 0 = female mean … 1 = male mean (0 or 1 when given).
    double gender_value() const { double v = 0; check(skb_result_gender_value(r_.get(), &v, nullptr)); return v; }
    /// Posterior probability that gender() is the right half (1 when given).
    double gender_confidence() const { double v = 0, c = 0; check(skb_result_gender_value(r_.get(), &v, &c)); return c; }
    /// True when the sketch supports less than half of the fitted outline (mostly clothing).
    bool low_evidence() const { bool l = false; check(skb_result_evidence(r_.get(), &l, nullptr)); return l; }
    /// Per body part (head, torso, right arm, left arm, right leg, left leg), the share of the
    /// fitted outline near a stroke (0..1; NaN out of view or for the mean shape);
    /// skb_result_copy_part_support.
    std::vector<double> part_support() const {
        std::vector<double> p(SKB_NUM_BODY_PARTS);
        check(skb_result_copy_part_support(r_.get(), p.data(), p.size()));
        return p;
    }
    /// Best match score of the fit; g must be gender() (throws otherwise).
    double score(uint32_t g) const { double s = 0; check(skb_result_score(r_.get(), g, &s)); return s; }
    size_t vertex_count() const { size_t v = 0; check(skb_result_vertex_count(r_.get(), &v)); return v; }
    size_t face_count() const { size_t f = 0; check(skb_result_face_count(r_.get(), &f)); return f; }
    /// x, y, z per vertex, metres (posed or rest).
    std::vector<float> vertices(bool posed) const {
        std::vector<float> v(3 * vertex_count());
        check(skb_result_copy_vertices(r_.get(), posed, v.data(), v.size()));
        return v;
    }
    /// 4 vertex indices per quad face.
    std::vector<uint32_t> faces() const {
        std::vector<uint32_t> f(4 * face_count());
        check(skb_result_copy_faces(r_.get(), f.data(), f.size()));
        return f;
    }
    skb_joints2d joints2d() const { skb_joints2d j{}; check(skb_result_joints2d(r_.get(), &j)); return j; }
    /// 45 doubles: SKB_JOINTS_REST, SKB_JOINTS_POSED or SKB_JOINTS_ESTIMATED.
    std::vector<double> joints3d(uint32_t which) const {
        std::vector<double> j(3 * SKB_NUM_JOINTS);
        check(skb_result_copy_joints3d(r_.get(), which, j.data(), j.size()));
        return j;
    }
    skb_camera camera() const { skb_camera c{}; check(skb_result_camera(r_.get(), &c)); return c; }
    SkinWeights skin_weights() const {
        SkinWeights s{std::vector<uint32_t>(SKB_MAX_INFLUENCES * vertex_count()), std::vector<float>(SKB_MAX_INFLUENCES * vertex_count())};
        check(skb_result_copy_skin_weights(r_.get(), s.bones.data(), s.weights.data(), s.bones.size()));
        return s;
    }
    std::vector<double> shape_weights() const {
        size_t n = 0;
        check(skb_result_shape_weight_count(r_.get(), &n));
        std::vector<double> w(n);
        check(skb_result_copy_shape_weights(r_.get(), w.data(), w.size()));
        return w;
    }
    /// The texture `sketchbody run` writes as body_texture.png: `sketch` (the colour image the
    /// result came from, e.g. LoadedColourImage::view()) projected through the result's camera
    /// onto its posed mesh; skb_result_project_texture.
    Texture texture(const skb_image &sketch, uint32_t size = SKB_DEFAULT_TEXTURE_SIZE) const {
        Texture t{size, std::vector<uint8_t>(3 * size_t(size) * size)};
        check(skb_result_project_texture(r_.get(), &sketch, size, t.rgb.data(), 3 * size_t(size), t.rgb.size(), nullptr,
                                         nullptr));
        return t;
    }
    /// The result's mesh (fitted rest shape, posed as in the result) for the mesh and rig getters.
    Mesh mesh() const {
        skb_mesh *raw = nullptr;
        check(skb_mesh_new_from_result(r_.get(), &raw));
        return Mesh(raw);
    }
    /// The number of ranked depth readings of the result's pose (alternative 0 is the pose).
    size_t alternative_count() const {
        skb_pose_estimate *e = nullptr;
        check(skb_pose_estimate_new_from_result(r_.get(), &e));
        Handle<skb_pose_estimate, skb_pose_estimate_free> h(e);
        size_t n = 0;
        check(skb_pose_estimate_alternative_count(h.get(), &n));
        return n;
    }
    /// Re-poses the fitted body in place to depth reading `index`, its shape kept
    /// (skb_result_pick_alternative). Returns the SKB_REPOSE_* outcome.
    uint32_t pick_alternative(uint32_t index) {
        uint32_t o = 0;
        check(skb_result_pick_alternative(r_.get(), index, &o));
        return o;
    }
    /// Flips limb `limb`'s depth (SKB_LIMB_*) and re-poses the fitted body in place, its shape
    /// kept (skb_result_flip_limb). Returns SKB_REPOSE_DONE or SKB_REPOSE_NO_DEPTH.
    uint32_t flip_limb(uint32_t limb) {
        uint32_t o = 0;
        check(skb_result_flip_limb(r_.get(), limb, &o));
        return o;
    }
    /// Re-poses the fitted body in place for moved 2-D joints, its shape kept (the live
    /// correction; skb_result_repose_joints with the embedded dictionary). Returns the
    /// SKB_REPOSE_* outcome (anything but SKB_REPOSE_DONE changed nothing).
    uint32_t repose(const skb_joints2d &joints) {
        uint32_t o = 0;
        check(skb_result_repose_joints(r_.get(), nullptr, &joints, &o));
        return o;
    }
    /// A turnaround's extra views, in the order given (empty for a one-view run).
    std::vector<skb_view_info> views() const {
        size_t n = 0;
        check(skb_result_view_count(r_.get(), &n));
        std::vector<skb_view_info> v(n);
        for (size_t k = 0; k < n; ++k) check(skb_result_view(r_.get(), k, &v[k]));
        return v;
    }
    /// What the run warns about its views, one per line (empty when none).
    std::string view_warnings() const {
        size_t n = 0;
        check(skb_result_view_warnings_length(r_.get(), &n));
        std::string s(n + 1, '\0');
        check(skb_result_copy_view_warnings(r_.get(), &s[0], s.size()));
        s.resize(n);
        return s;
    }
    const skb_result *get() const noexcept { return r_.get(); }

private:
    Handle<skb_result, skb_result_free> r_;
};

/// Runs the main job (skb_pipeline_run) with the embedded pose dictionary and default pose
/// options. `joints` may be nullptr: the embedded detector finds them (SKB_ERR_NO_FIGURE if none).
inline Result run_pipeline(const Context &ctx, const skb_image &sketch, const skb_joints2d *joints,
                           const FitOptions *fit = nullptr, Progress progress = {}) {
    skb_result *raw = nullptr;
    skb_progress_fn fn = progress ? &detail::progress_trampoline : nullptr;
    check(skb_pipeline_run(ctx.get(), &sketch, joints, nullptr, nullptr, fit ? fit->get() : nullptr, fn,
                           progress ? static_cast<void *>(&progress) : nullptr, &raw));
    return Result(raw);
}

/// Interim-body callback of run_pipeline_progressive: the stage (SKB_INTERIM_MEAN_SHAPE,
/// SKB_INTERIM_DECIDING_FIT) and a copy of the body's posed vertices (x, y, z per vertex, metres).
using Interim = std::function<void(uint32_t stage, const std::vector<float> &posed_vertices)>;

namespace detail {
/// The progress and interim callbacks of one progressive run (they share the C `user`).
struct ProgressiveCallbacks {
    Progress progress;
    Interim interim;
    bool failed = false;  ///< an interim callback threw: the next progress call cancels
};
inline int progressive_progress(void *user, float fraction) {
    auto *c = static_cast<ProgressiveCallbacks *>(user);
    if (c->failed) return 1;
    return c->progress ? progress_trampoline(&c->progress, fraction) : 0;
}
inline void progressive_interim(void *user, uint32_t stage, const skb_mesh *mesh) {
    auto *c = static_cast<ProgressiveCallbacks *>(user);
    if (c->failed) return;
    try {
        size_t n = 0;
        check(skb_mesh_vertex_count(mesh, &n));
        std::vector<float> v(3 * n);
        check(skb_mesh_copy_posed_vertices(mesh, v.data(), v.size()));
        c->interim(stage, v);
    } catch (...) {
        c->failed = true;  // an exception in the callback cancels the run
    }
}
}  // namespace detail

/// run_pipeline that also hands `interim` the bodies it has before the final one
/// (skb_pipeline_run_progressive): the mean shape in the estimated pose, then the deciding fit.
inline Result run_pipeline_progressive(const Context &ctx, const skb_image &sketch, const skb_joints2d *joints,
                                       const FitOptions *fit, Interim interim, Progress progress = {}) {
    skb_result *raw = nullptr;
    detail::ProgressiveCallbacks c{std::move(progress), std::move(interim)};
    check(skb_pipeline_run_progressive(ctx.get(), &sketch, joints, nullptr, nullptr, fit ? fit->get() : nullptr,
                                       &detail::progressive_progress, c.interim ? &detail::progressive_interim : nullptr,
                                       &c, &raw));
    return Result(raw);
}

/// One extra view of a turnaround for run_pipeline_views: its label (SKB_VIEW_SIDE,
/// SKB_VIEW_SIDE_LEFT, SKB_VIEW_BACK), its sketch and its joints (nullptr: detected); the
/// image and joints are borrowed for the call.
struct View {
    uint32_t label;
    skb_image sketch;
    const skb_joints2d *joints = nullptr;
};

/// run_pipeline_progressive on a turnaround (skb_pipeline_run_views): `sketch` and `joints` the
/// front view, `views` the same character in the same pose from the side or the back. Views that
/// do not show one character in one pose throw Error with SKB_ERR_VIEWS_DISAGREE.
inline Result run_pipeline_views(const Context &ctx, const skb_image &sketch, const skb_joints2d *joints,
                                 const std::vector<View> &views, const FitOptions *fit = nullptr, Interim interim = {},
                                 Progress progress = {}) {
    std::vector<skb_view_input> in;
    in.reserve(views.size());
    for (const View &v : views) in.push_back(skb_view_input{v.label, 0, &v.sketch, v.joints});
    skb_result *raw = nullptr;
    detail::ProgressiveCallbacks c{std::move(progress), std::move(interim)};
    check(skb_pipeline_run_views(ctx.get(), &sketch, joints, in.empty() ? nullptr : in.data(), in.size(), nullptr,
                                 nullptr, fit ? fit->get() : nullptr, &detail::progressive_progress,
                                 c.interim ? &detail::progressive_interim : nullptr, &c, &raw));
    return Result(raw);
}

}  // namespace sketchbody

#endif  // SKETCHBODY_HPP
