/* The CLI's textured result reproduced from C (built -Wall -Wextra -Werror under ASan + UBSan):
 * `sketchbody run` on the bundled example (given joints, male, a small fit, a 256-texel texture,
 * FBX and USD in centimetres, Z up) and the same job through the C API
 * (skb_rgb_image_new_from_file, skb_joints2d_read_json, skb_pipeline_run with the same fit settings,
 * skb_result_project_texture, skb_image_write_png) must give the same body_texture.png, byte for
 * byte and pixel for pixel; skb_mesh_project_texture with skb_mesh_new_from_result and skb_result_camera
 * the same pixels; skb_mesh_write_usd / skb_mesh_write_fbx with skb_export_options_set_units(cm) and
 * _set_up_axis(Z) the CLI's points and metadata (`metersPerUnit = 0.01`, `upAxis = "Z"`) and the
 * FBX's UnitScaleFactor 1 / UpAxis 2. Bad input: an unknown unit or axis, a texture size of 0,
 * a short buffer and an unwritable PNG path each give their status and write nothing.
 * Usage: capi_texture_test CLI SKETCH.png JOINTS.json */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sketchbody.h"

#include "c_check.h"

enum { SIZE = 256, STRIDE = 3 * SIZE + 5, LEN = STRIDE * (SIZE - 1) + 3 * SIZE };

/* The whole file at `path` into a malloc'd buffer (NUL-terminated); NULL when unreadable. */
static char *slurp(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    size_t got = fread(buf, 1, (size_t)n, f);
    fclose(f);
    buf[got] = 0;
    if (len) *len = got;
    return buf;
}

/* The line of `text` holding `key` (up to its newline), malloc'd; NULL when absent. */
static char *line_of(const char *text, const char *key) {
    const char *at = text ? strstr(text, key) : NULL;
    if (!at) return NULL;
    const char *end = strchr(at, '\n');
    size_t n = end ? (size_t)(end - at) : strlen(at);
    char *out = malloc(n + 1);
    memcpy(out, at, n);
    out[n] = 0;
    return out;
}

/* True when the bytes `needle` (n bytes) occur in `hay`. */
static int contains(const char *hay, size_t len, const char *needle, size_t n) {
    for (size_t i = 0; i + n <= len; ++i)
        if (memcmp(hay + i, needle, n) == 0) return 1;
    return 0;
}

/* Where the value of the FBX `Properties70` entry `name` starts (its type code): the entry is
 * P: name (S), type (S), label (S), flags (S), then the value. 0 when absent. */
static size_t fbx_value_at(const char *data, size_t len, const char *name) {
    size_t n = strlen(name);
    for (size_t i = 5; i + n < len; ++i) {
        uint32_t slen;
        memcpy(&slen, data + i - 4, 4);
        if (data[i - 5] != 'S' || slen != n || memcmp(data + i, name, n) != 0) continue;
        size_t at = i + n;
        for (int k = 0; k < 3; ++k) {
            if (at + 5 > len || data[at] != 'S') return 0;
            memcpy(&slen, data + at + 1, 4);
            at += 5 + slen;
        }
        return at + 9 <= len ? at : 0;
    }
    return 0;
}

/* The int32 (`I`) value of the entry `name`. */
static int fbx_int(const char *data, size_t len, const char *name, int32_t *value) {
    size_t at = fbx_value_at(data, len, name);
    if (!at || data[at] != 'I') return 0;
    memcpy(value, data + at + 1, 4);
    return 1;
}

/* The double (`D`) value of the entry `name`. */
static int fbx_double(const char *data, size_t len, const char *name, double *value) {
    size_t at = fbx_value_at(data, len, name);
    if (!at || data[at] != 'D') return 0;
    memcpy(value, data + at + 1, 8);
    return 1;
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: %s CLI SKETCH.png JOINTS.json\n", argv[0]);
        return 2;
    }
    const char *cli = argv[1], *sketch = argv[2], *joints_path = argv[3];
    if (access(cli, X_OK) != 0) {
        fprintf(stderr, "FAILED: the CLI %s is not built (cmake builds it with the library)\n", cli);
        return 1;
    }
    char dir[] = "/tmp/skb-texture-XXXXXX";
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    char out[4096], cmd[16384], path[4200];
    snprintf(out, sizeof out, "%s/cli", dir);
    snprintf(cmd, sizeof cmd,
             "'%s' run '%s' --joints '%s' --gender m --out '%s' --samples 24 --iterations 2 --quiet "
             "--preview-size=128 --texture-size %d --format glb,fbx,usd --units cm --up z",
             cli, sketch, joints_path, out, SIZE);
    printf("running: %s\n", cmd);
    CHECK(system(cmd) == 0);

    /* The same job through the C API. */
    skb_context *ctx = NULL;
    CHECK(skb_context_new(&ctx) == SKB_OK);
    skb_rgb_image *rgb = NULL;
    CHECK(skb_rgb_image_new_from_file(sketch, &rgb) == SKB_OK);
    skb_image view;
    CHECK(skb_rgb_image_view(rgb, &view) == SKB_OK);
    CHECK(view.channels == 3 && view.stride == 3 * view.width);
    skb_joints2d joints;
    CHECK(skb_joints2d_read_json(joints_path, &joints) == SKB_OK);
    skb_fit_options *fit = NULL;
    CHECK(skb_fit_options_new(&fit) == SKB_OK);
    CHECK(skb_fit_options_set_samples(fit, 24) == SKB_OK);
    CHECK(skb_fit_options_set_iterations(fit, 2) == SKB_OK);
    CHECK(skb_fit_options_set_gender(fit, SKB_GENDER_MALE) == SKB_OK);
    skb_result *result = NULL;
    skb_status st = skb_pipeline_run(ctx, &view, &joints, NULL, NULL, fit, NULL, NULL, &result);
    CHECK(st == SKB_OK);
    if (st != SKB_OK) {
        fprintf(stderr, "skb_pipeline_run: %s\n", skb_last_error_message());
        return 1;
    }

    /* The texture: the result's projection, written with the library's PNG encoder. */
    uint8_t *tex = malloc(LEN);
    memset(tex, 0xA5, LEN);
    uint64_t texels = 0, visible = 0;
    CHECK(skb_result_project_texture(result, &view, SIZE, tex, STRIDE, LEN, &texels, &visible) == SKB_OK);
    printf("texture %dx%d: %llu texels in the UV layout, %llu coloured by the sketch\n", SIZE, SIZE,
           (unsigned long long)texels, (unsigned long long)visible);
    CHECK(texels > 0.3 * SIZE * SIZE && visible > 0.05 * texels && visible < texels);
    CHECK(tex[3 * SIZE] == 0xA5 && tex[STRIDE - 1] == 0xA5); /* the row padding is not written */
    skb_image tex_view = {tex, SIZE, SIZE, STRIDE, 3};
    snprintf(path, sizeof path, "%s/c_texture.png", dir);
    CHECK(skb_image_write_png(&tex_view, path) == SKB_OK);
    size_t cli_len = 0, c_len = 0;
    snprintf(cmd, sizeof cmd, "%s/body_texture.png", out);
    char *cli_png = slurp(cmd, &cli_len);
    char *c_png = slurp(path, &c_len);
    CHECK(cli_png && c_png && cli_len == c_len && cli_len > 100 && memcmp(cli_png, c_png, cli_len) == 0);
    printf("body_texture.png: CLI %zu bytes, C %zu bytes, %s\n", cli_len, c_len,
           cli_png && c_png && cli_len == c_len && memcmp(cli_png, c_png, cli_len) == 0 ? "identical" : "DIFFERENT");
    /* Pixel for pixel, the CLI's file decoded by the library. */
    skb_rgb_image *cli_img = NULL;
    CHECK(skb_rgb_image_new_from_file(cmd, &cli_img) == SKB_OK);
    skb_image cv;
    CHECK(skb_rgb_image_view(cli_img, &cv) == SKB_OK);
    CHECK(cv.width == SIZE && cv.height == SIZE);
    long differ = 0, first = -1;
    for (int y = 0; y < SIZE && cv.width == SIZE && cv.height == SIZE; ++y)
        for (int x = 0; x < 3 * SIZE; ++x)
            if (cv.data[y * cv.stride + x] != tex[y * STRIDE + x]) {
                if (first < 0) first = y * 3 * SIZE + x;
                ++differ;
            }
    printf("pixels: %ld of %d bytes differ (first at byte %ld)\n", differ, 3 * SIZE * SIZE, first);
    CHECK(differ == 0);

    /* The same from a mesh and camera of the result. */
    skb_mesh *mesh = NULL;
    CHECK(skb_mesh_new_from_result(result, &mesh) == SKB_OK);
    skb_camera cam;
    CHECK(skb_result_camera(result, &cam) == SKB_OK);
    uint8_t *tex2 = malloc(3 * SIZE * SIZE);
    uint64_t visible2 = 0;
    CHECK(skb_mesh_project_texture(mesh, &view, &cam, SIZE, tex2, 3 * SIZE, 3 * SIZE * SIZE, NULL, &visible2) ==
          SKB_OK);
    int same = visible2 == visible;
    for (int y = 0; y < SIZE; ++y) same &= memcmp(tex2 + y * 3 * SIZE, tex + y * STRIDE, 3 * SIZE) == 0;
    CHECK(same);

    /* Bad input: nothing written. */
    memset(tex2, 0x5A, 3 * SIZE * SIZE);
    CHECK(skb_result_project_texture(result, &view, 0, tex2, 3 * SIZE, 3 * SIZE * SIZE, NULL, NULL) ==
          SKB_ERR_OUT_OF_RANGE);
    CHECK(skb_result_project_texture(result, &view, SIZE, tex2, 3 * SIZE, 3 * SIZE * SIZE - 1, NULL, NULL) ==
          SKB_ERR_BUFFER_TOO_SMALL);
    CHECK(strstr(skb_last_error_message(), "dst") != NULL);
    CHECK(tex2[0] == 0x5A && tex2[3 * SIZE * SIZE - 1] == 0x5A);
    snprintf(path, sizeof path, "%s/no/such/folder/t.png", dir);
    CHECK(skb_image_write_png(&tex_view, path) == SKB_ERR_IO);

    /* FBX and USD in centimetres, Z up, as the CLI's --units cm --up z. */
    skb_export_options *eo = NULL;
    CHECK(skb_export_options_new(&eo) == SKB_OK);
    CHECK(skb_export_options_set_units(eo, 7) == SKB_ERR_OUT_OF_RANGE);
    CHECK(strstr(skb_last_error_message(), "units") != NULL);
    CHECK(skb_export_options_set_up_axis(eo, 2) == SKB_ERR_OUT_OF_RANGE);
    CHECK(strstr(skb_last_error_message(), "up axis") != NULL);
    CHECK(skb_export_options_set_units(eo, SKB_UNITS_CENTIMETRES) == SKB_OK);
    CHECK(skb_export_options_set_up_axis(eo, SKB_UP_Z) == SKB_OK);
    /* The CLI's run writes twist bones and shape keys by default; the C API asks for them. */
    CHECK(skb_export_options_set_twist_bones(eo, true) == SKB_OK);
    CHECK(skb_export_options_set_shape_keys(eo, true) == SKB_OK);
    snprintf(path, sizeof path, "%s/c.usda", dir);
    CHECK(skb_mesh_write_usd(mesh, path, eo) == SKB_OK);
    char *c_usd = slurp(path, NULL);
    snprintf(cmd, sizeof cmd, "%s/body.usda", out);
    char *cli_usd = slurp(cmd, NULL);
    CHECK(c_usd && strstr(c_usd, "metersPerUnit = 0.01\n") && strstr(c_usd, "upAxis = \"Z\"\n"));
    char *c_points = line_of(c_usd, "point3f[] points = "), *cli_points = line_of(cli_usd, "point3f[] points = ");
    CHECK(c_points && cli_points && strcmp(c_points, cli_points) == 0);
    char *c_bind = line_of(c_usd, "bindTransforms = "), *cli_bind = line_of(cli_usd, "bindTransforms = ");
    CHECK(c_bind && cli_bind && strcmp(c_bind, cli_bind) == 0);
    char *c_keys = line_of(c_usd, "uniform token[] skel:blendShapes = "),
         *cli_keys = line_of(cli_usd, "uniform token[] skel:blendShapes = ");
    CHECK(c_keys && cli_keys && strcmp(c_keys, cli_keys) == 0);
    free(c_keys), free(cli_keys);
    snprintf(path, sizeof path, "%s/c.fbx", dir);
    CHECK(skb_mesh_write_fbx(mesh, path, eo) == SKB_OK);
    size_t fbx_len = 0;
    char *fbx = slurp(path, &fbx_len);
    int32_t up = -1, front = -1, front_sign = 0;
    double unit = -1;
    CHECK(fbx && fbx_int(fbx, fbx_len, "UpAxis", &up) && fbx_int(fbx, fbx_len, "FrontAxis", &front) &&
          fbx_int(fbx, fbx_len, "FrontAxisSign", &front_sign) && fbx_double(fbx, fbx_len, "UnitScaleFactor", &unit));
    printf("FBX: UpAxis %d, FrontAxis %d sign %d, UnitScaleFactor %g\n", up, front, front_sign, unit);
    CHECK(up == 2 && front == 1 && front_sign == -1 && unit == 1.0);
    CHECK(fbx && contains(fbx, fbx_len, "Kaydara FBX Binary", 18));

    free(c_points), free(cli_points), free(c_bind), free(cli_bind), free(c_usd), free(cli_usd), free(fbx);
    free(cli_png), free(c_png), free(tex), free(tex2);
    skb_export_options_free(eo);
    skb_mesh_free(mesh);
    skb_rgb_image_free(cli_img);
    skb_result_free(result);
    skb_fit_options_free(fit);
    skb_rgb_image_free(rgb);
    skb_context_free(ctx);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
    if (failures) {
        fprintf(stderr, "%d check(s) FAILED\n", failures);
        return 1;
    }
    printf("capi_texture_test: all checks passed\n");
    return 0;
}
