// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Tissue that nothing holds: boxes A (fixed) and B (rigid) with tissue 'web'
// between them, boxes C and D (both rigid) with tissue 'loose' between them,
// far from A and B. 'loose' and the two bodies it joins would fall for ever:
// prep refuses the scene naming the tissue and its volume. Without 'loose'
// the model is built, holds no unheld piece and reports none dropped.
// Last, one tissue in two pieces: A (fixed) between the two boxes of the
// rigid organ B, 4 mm from one and 6 mm from the other; the 6 mm layer gets
// no frame on either surface (3 mm frame spacing), so nothing holds it: it is
// dropped, listed, and the model left is whole and held.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include "check.h"
#include "prep_fixture.h"

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "   {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"rigid\"},\n"
    "   {\"name\": \"C\", \"mesh\": \"c.obj\", \"model\": \"rigid\"},\n"
    "   {\"name\": \"D\", \"mesh\": \"d.obj\", \"model\": \"rigid\"}],\n"
    " \"tissues\": [{\"name\": \"web\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.005, \"material\": \"soft\",\n"
    "   \"frame_spacing\": 0.002, \"sample_spacing\": 0.0015}%s]}\n";
static const char loose[] = ",\n  {\"name\": \"loose\", \"connects\": [\"C\", \"D\"], \"max_gap\": 0.005, "
                            "\"material\": \"soft\", \"frame_spacing\": 0.002, \"sample_spacing\": 0.0015}";

int main(void) {
  char dir[256], path[512], text[2048];
  if (!fixture_tmpdir(dir)) return 1;
  const double lo[4][3] = {{-0.03, -0.01, -0.01}, {0.002, -0.01, -0.01}, {-0.03, -0.01, 0.06}, {0.002, -0.01, 0.06}};
  const double hi[4][3] = {{-0.002, 0.01, 0.01}, {0.03, 0.01, 0.01}, {-0.002, 0.01, 0.08}, {0.03, 0.01, 0.08}};
  const char *names[] = {"a.obj", "b.obj", "c.obj", "d.obj", "scene.json", NULL};
  for (int k = 0; k < 4; ++k) CHECK(fixture_box(dir, names[k], lo[k], hi[k]));
  snprintf(path, sizeof path, "%s/scene.json", dir);

  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  snprintf(text, sizeof text, scene_format, loose);
  CHECK(fixture_write(dir, "scene.json", text));
  const fascia_status st = fixture_prep(ctx, path, &r);
  const char *msg = fascia_ctx_message(ctx);
  fprintf(stderr, "with 'loose': %s: %s\n", fascia_status_name(st), msg);
  CHECK(st == FASCIA_ERR_ARGUMENT);
  CHECK(r.model == NULL);
  CHECK(strstr(msg, "tissue 'loose'") && strstr(msg, "cm^3") && strstr(msg, "nothing holds it") &&
        strstr(msg, "scene.json"));
  fixture_free(&r);

  snprintf(text, sizeof text, scene_format, "");
  CHECK(fixture_write(dir, "scene.json", text));
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  int32_t count = -1;
  CHECK_OK(fascia_model_floating_components(ctx, r.model, NULL, NULL, 0, &count), ctx);
  CHECK(count == 0);
  CHECK(r.model->provenance && strstr(r.model->provenance, "\"unheld_pieces_dropped\":[]"));
  fixture_free(&r);

  // one tissue, two pieces, one of them held by nothing
  static const char two_pieces[] =
      "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
      " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
      " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
      "   {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"rigid\"}],\n"
      " \"tissues\": [{\"name\": \"web\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.005, "
      "\"material\": \"soft\", \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015}]}\n";
  const double a_lo[3] = {-0.01, -0.01, -0.01}, a_hi[3] = {0.01, 0.01, 0.01};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi));
  char obj[1024];
  snprintf(obj, sizeof obj, "%s/b.obj", dir);
  FILE *f = fopen(obj, "w");
  CHECK(f != NULL);
  const double b_lo[2][3] = {{0.014, -0.01, -0.01}, {-0.04, -0.01, -0.01}};
  const double b_hi[2][3] = {{0.04, 0.01, 0.01}, {-0.016, 0.01, 0.01}};
  static const int quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (int b = 0; f && b < 2; ++b) {
    for (int v = 0; v < 8; ++v)
      fprintf(f, "v %g %g %g\n", v & 4 ? b_hi[b][0] : b_lo[b][0], v & 2 ? b_hi[b][1] : b_lo[b][1],
              v & 1 ? b_hi[b][2] : b_lo[b][2]);
    for (int q = 0; q < 6; ++q) {
      const int *k = quads[q], o = 8 * b + 1;
      fprintf(f, "f %d %d %d\nf %d %d %d\n", o + k[0], o + k[1], o + k[3], o + k[1], o + k[2], o + k[3]);
    }
  }
  if (f) fclose(f);
  CHECK(fixture_write(dir, "scene.json", two_pieces));
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  CHECK_OK(fascia_model_floating_components(ctx, r.model, NULL, NULL, 0, &count), ctx);
  CHECK(count == 0);
  const char *list = r.model->provenance ? strstr(r.model->provenance, "\"unheld_pieces_dropped\":[{") : NULL;
  CHECK(list && strstr(list, "\"tissue\":\"web\"") && strstr(list, "\"frames\":"));
  fprintf(stderr, "two pieces: %d of %d frames and %d of %d samples kept\n", (int)r.model->frame_count,
          (int)r.points->frame_count, (int)r.model->sample_count, (int)r.points->sample_count);
  CHECK(r.model->frame_count < r.points->frame_count && r.model->sample_count < r.points->sample_count);
  CHECK(r.model->frame_count > 0 && r.model->coupling_count == r.coupling->count); // the held piece keeps its coupling
  fixture_free(&r);

  fascia_ctx_destroy(&ctx);
  fixture_cleanup(dir, names);
  return check_failures_ != 0;
}
