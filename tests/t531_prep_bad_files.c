// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Input files that `fascia prep` (the CLI, argv[1]) must refuse up front,
// with one line naming the file and the problem, instead of hanging or
// reading a part of them: a folder, a FIFO or a device as the scene or
// a mesh, a scene far larger than any scene, and STL files cut short or garbled (ASCII without "endsolid" or
// with a facet cut short, binary whose size disagrees with its triangle
// count) and PLY files whose body holds less than their header declares.
// The complete files, ASCII and binary, are accepted. A face index out of
// range, which assimp clamps or drops silently, is refused: OFF (the vertex
// count, -1, 2^32, 99999, fewer faces than declared), glTF (an index past
// the vertices), OBJ (a NUL inside a face line, index 0, past the end).
#define _POSIX_C_SOURCE 200809L // mkdtemp, mkfifo, WEXITSTATUS
#include <sys/stat.h>
#include <unistd.h>

#include "prep_cli_case.h"

static char dir[256];

// Box B of the scene, [0.003, 0.02] x [-0.01, 0.01]^2, as 12 outward triangles.
static void box_triangles(float tri[12][3][3]) {
  static const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (int f = 0; f < 6; ++f)
    for (int h = 0; h < 2; ++h) {
      const int corner[3] = {quads[f][0], quads[f][1 + h], quads[f][2 + h]};
      for (int k = 0; k < 3; ++k) {
        const int c = corner[k];
        tri[2 * f + h][k][0] = (c & 1) ? 0.02f : 0.003f;
        tri[2 * f + h][k][1] = (c & 2) ? 0.01f : -0.01f;
        tri[2 * f + h][k][2] = (c & 4) ? 0.01f : -0.01f;
      }
    }
}

// The ASCII STL of box B; cut_facet >= 0: cut before vertex cut_vertex of
// that facet (0 .. 3, 3: before its "endloop"); no_end: without the
// "endsolid" line; garble: the text of facet 5 vertex 1's z coordinate.
static int write_ascii_stl(const char *name, int cut_facet, int cut_vertex, int no_end, const char *garble) {
  float tri[12][3][3];
  box_triangles(tri);
  static char text[8192];
  int n = snprintf(text, sizeof text, "solid b\n");
  for (int t = 0; t < 12; ++t) {
    n += snprintf(text + n, sizeof text - (size_t)n, "  facet normal 0 0 0\n    outer loop\n");
    for (int k = 0; k < 3; ++k) {
      if (t == cut_facet && k == cut_vertex) return fixture_write(dir, name, text);
      char z[32];
      snprintf(z, sizeof z, "%g", tri[t][k][2]);
      n += snprintf(text + n, sizeof text - (size_t)n, "      vertex %g %g %s\n", tri[t][k][0], tri[t][k][1],
                    garble && t == 5 && k == 1 ? garble : z);
    }
    if (t == cut_facet) return fixture_write(dir, name, text);
    n += snprintf(text + n, sizeof text - (size_t)n, "    endloop\n  endfacet\n");
  }
  if (!no_end) snprintf(text + n, sizeof text - (size_t)n, "endsolid b\n");
  return fixture_write(dir, name, text);
}

// The binary STL of box B with a header starting with `header`, its size
// changed by `extra` bytes (negative: cut).
static int write_binary_stl(const char *name, const char *header, int extra) {
  float tri[12][3][3];
  box_triangles(tri);
  unsigned char data[84 + 50 * 12 + 64] = {0};
  memcpy(data, header, strlen(header));
  data[80] = 12;
  for (int t = 0; t < 12; ++t) memcpy(data + 84 + 50 * t + 12, tri[t], 36); // normal 0, 3 vertices, no attribute
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  const size_t size = (size_t)(84 + 50 * 12 + extra);
  const int ok = fwrite(data, 1, size, f) == size;
  return fclose(f) == 0 && ok;
}

// Box B as a PLY (ASCII or little-endian binary), its body cut by cut bytes.
static int write_ply(const char *name, int binary, int cut) {
  float tri[12][3][3];
  box_triangles(tri);
  static char data[8192];
  int n = snprintf(data, sizeof data,
                   "ply\nformat %s 1.0\ncomment box B, three vertices per triangle\nelement vertex 36\n"
                   "property float x\nproperty float y\nproperty float z\nelement face 12\n"
                   "property list uchar int vertex_indices\nend_header\n",
                   binary ? "binary_little_endian" : "ascii");
  for (int t = 0; t < 12; ++t)
    for (int k = 0; k < 3; ++k) {
      if (binary) {
        memcpy(data + n, tri[t][k], 12);
        n += 12;
      } else {
        n += snprintf(data + n, sizeof data - (size_t)n, "%g %g %g\n", tri[t][k][0], tri[t][k][1], tri[t][k][2]);
      }
    }
  for (int t = 0; t < 12; ++t) {
    const int32_t v[3] = {3 * t, 3 * t + 1, 3 * t + 2};
    if (binary) {
      data[n++] = 3;
      memcpy(data + n, v, 12);
      n += 12;
    } else {
      n += snprintf(data + n, sizeof data - (size_t)n, "3 %d %d %d\n", (int)v[0], (int)v[1], (int)v[2]);
    }
  }
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  const int ok = fwrite(data, 1, (size_t)(n - cut), f) == (size_t)(n - cut);
  return fclose(f) == 0 && ok;
}

// Box B as 8 corners and 12 triangles; bad: replaces face 5's second index.
static void box_indexed(float v[8][3], int f[12][3]) {
  static const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (int c = 0; c < 8; ++c) {
    v[c][0] = (c & 1) ? 0.02f : 0.003f;
    v[c][1] = (c & 2) ? 0.01f : -0.01f;
    v[c][2] = (c & 4) ? 0.01f : -0.01f;
  }
  for (int q = 0; q < 6; ++q)
    for (int h = 0; h < 2; ++h) f[2 * q + h][0] = quads[q][0], f[2 * q + h][1] = quads[q][1 + h], f[2 * q + h][2] = quads[q][2 + h];
}

// OFF of box B; face 5's second index is the text bad when given; faces: the count declared
static int write_off(const char *name, const char *bad, int faces) {
  float v[8][3];
  int f[12][3];
  box_indexed(v, f);
  char text[4096];
  int n = snprintf(text, sizeof text, "OFF\n8 %d 0\n", faces);
  for (int c = 0; c < 8; ++c) n += snprintf(text + n, sizeof text - (size_t)n, "%g %g %g\n", v[c][0], v[c][1], v[c][2]);
  for (int k = 0; k < 12; ++k) {
    char second[32];
    snprintf(second, sizeof second, "%d", f[k][1]);
    n += snprintf(text + n, sizeof text - (size_t)n, "3 %d %s %d\n", f[k][0], k == 5 && bad ? bad : second, f[k][2]);
  }
  return fixture_write(dir, name, text);
}

// OBJ of box B; face 5's line is bad (n bytes, may hold a NUL) when given
static int write_obj(const char *name, const char *bad, size_t bad_size) {
  float v[8][3];
  int f[12][3];
  box_indexed(v, f);
  char text[4096];
  size_t n = 0;
  for (int c = 0; c < 8; ++c) n += (size_t)snprintf(text + n, sizeof text - n, "v %g %g %g\n", v[c][0], v[c][1], v[c][2]);
  for (int k = 0; k < 12; ++k) {
    if (k == 5 && bad) {
      memcpy(text + n, bad, bad_size);
      n += bad_size;
      text[n++] = '\n';
    } else {
      n += (size_t)snprintf(text + n, sizeof text - n, "f %d %d %d\n", f[k][0] + 1, f[k][1] + 1, f[k][2] + 1);
    }
  }
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *out = fopen(path, "wb");
  const int ok = out && fwrite(text, 1, n, out) == n;
  return out && fclose(out) == 0 && ok;
}

// glTF of box B with its buffer inline (base64); face 5's second index is bad when >= 0
static int write_gltf(const char *name, int bad) {
  float v[8][3];
  int f[12][3];
  box_indexed(v, f);
  unsigned char buf[8 * 12 + 36 * 2];
  memcpy(buf, v, sizeof v); // little-endian floats, as glTF stores them
  for (int k = 0; k < 36; ++k) {
    const int i = (k == 16 && bad >= 0) ? bad : f[k / 3][k % 3];
    buf[96 + 2 * k] = (unsigned char)(i & 255), buf[96 + 2 * k + 1] = (unsigned char)(i >> 8);
  }
  static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  char enc[256];
  size_t e = 0;
  for (size_t k = 0; k < sizeof buf; k += 3) {
    const unsigned w = (unsigned)buf[k] << 16 | (unsigned)(k + 1 < sizeof buf ? buf[k + 1] : 0) << 8 |
                       (unsigned)(k + 2 < sizeof buf ? buf[k + 2] : 0);
    enc[e++] = b64[w >> 18 & 63], enc[e++] = b64[w >> 12 & 63];
    enc[e++] = k + 1 < sizeof buf ? b64[w >> 6 & 63] : '=';
    enc[e++] = k + 2 < sizeof buf ? b64[w & 63] : '=';
  }
  enc[e] = 0;
  char text[4096];
  snprintf(text, sizeof text,
           "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}],\n"
           " \"nodes\": [{\"mesh\": 0, \"name\": \"b\"}],\n"
           " \"meshes\": [{\"name\": \"b\", \"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, \"mode\": 4}]}],\n"
           " \"buffers\": [{\"byteLength\": 168, \"uri\": \"data:application/octet-stream;base64,%s\"}],\n"
           " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 96},\n"
           "                 {\"buffer\": 0, \"byteOffset\": 96, \"byteLength\": 72}],\n"
           " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 8, \"type\": \"VEC3\",\n"
           "                \"min\": [0.003, -0.01, -0.01], \"max\": [0.02, 0.01, 0.01]},\n"
           "               {\"bufferView\": 1, \"componentType\": 5123, \"count\": 36, \"type\": \"SCALAR\"}]}\n",
           enc);
  return fixture_write(dir, name, text);
}

static void refused(const char *cli, const char *name, const char *mesh_b, const char *e1, const char *e2,
                    const char *e3) {
  prep_case_mesh(cli, dir, name, mesh_b, (const char *const[]){"organs[1].mesh", e1, e2, e3, NULL});
}

static void accepted(const char *cli, const char *name, const char *mesh_b) {
  CHECK(prep_case_mesh(cli, dir, name, mesh_b, NULL));
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t531_prep_bad_files PATH_TO_FASCIA\n");
    return 1;
  }
  const char *cli = argv[1];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-0.02, -0.01, -0.01}, a_hi[3] = {-0.003, 0.01, 0.01};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi));
  char sub[512], fifo[512];
  snprintf(sub, sizeof sub, "%s/folder.obj", dir);
  snprintf(fifo, sizeof fifo, "%s/pipe.obj", dir);
  CHECK(mkdir(sub, 0700) == 0 && mkfifo(fifo, 0600) == 0);

  // not regular files, as a mesh: refused before anything reads them
  refused(cli, "folder as mesh", "folder.obj", "folder.obj", "is a folder", 0);
  refused(cli, "FIFO as mesh", "pipe.obj", "pipe.obj", "FIFO (named pipe)", 0);
  refused(cli, "/dev/zero as mesh", "/dev/zero", "/dev/zero", "character device", 0);
  // ... and as the scene
  prep_case_refused(cli, dir, "folder as scene", sub, (const char *const[]){"scene", "is a folder", NULL});
  prep_case_refused(cli, dir, "FIFO as scene", fifo, (const char *const[]){"scene", "FIFO (named pipe)", NULL});
  prep_case_refused(cli, dir, "/dev/zero as scene", "/dev/zero",
                    (const char *const[]){"scene '/dev/zero'", "character device", NULL});

  // a scene larger than a scene can be is not read into memory (a sparse file: no disk used)
  char big[512];
  snprintf(big, sizeof big, "%s/big.json", dir);
  CHECK(fixture_write(dir, "big.json", "{") && truncate(big, (off_t)65 << 20) == 0);
  prep_case_refused(cli, dir, "scene of 65 MiB", big,
                    (const char *const[]){"big.json", "68157440 bytes", "more than the 67108864", NULL});

  // STL: complete files are read
  CHECK(write_ascii_stl("b.stl", -1, 0, 0, NULL));
  accepted(cli, "ASCII STL", "b.stl");
  CHECK(write_binary_stl("bin.stl", "binary box", 0));
  accepted(cli, "binary STL", "bin.stl");
  CHECK(write_binary_stl("solid.STL", "solid box, binary", 0)); // a binary header may start with "solid"
  accepted(cli, "binary STL with a 'solid' header", "solid.STL");

  // ... damaged ones are refused, naming the problem
  CHECK(write_ascii_stl("noend.stl", -1, 0, 1, NULL));
  refused(cli, "ASCII STL without endsolid", "noend.stl", "noend.stl", "truncated", "no \"endsolid\"");
  CHECK(write_ascii_stl("cut.stl", 4, 2, 0, NULL));
  refused(cli, "ASCII STL cut in a facet", "cut.stl", "cut short at line", "after 4 complete facets", "\"vertex\"");
  CHECK(write_ascii_stl("garbled.stl", -1, 0, 0, "zero"));
  refused(cli, "ASCII STL with a word for a number", "garbled.stl", "line 40", "found 'zero'", "coordinates");
  CHECK(write_binary_stl("short.stl", "binary box", -30));
  refused(cli, "binary STL cut short", "short.stl", "counts 12 triangles", "684 bytes", "has 654 bytes");
  CHECK(write_binary_stl("long.stl", "binary box", 20));
  refused(cli, "binary STL too long", "long.stl", "counts 12 triangles", "has 704 bytes", 0);
  CHECK(write_binary_stl("solidshort.stl", "solid box, binary", -50));
  refused(cli, "binary STL with a 'solid' header, cut short", "solidshort.stl", "binary STL", "has 634 bytes", 0);
  CHECK(write_binary_stl("tiny.stl", "", -(50 * 12 + 10)));
  refused(cli, "STL shorter than its header", "tiny.stl", "74 bytes", "84-byte header", 0);

  // PLY: the body must hold what the header declares
  CHECK(write_ply("b.ply", 0, 0) && write_ply("bin.ply", 1, 0));
  accepted(cli, "ASCII PLY", "b.ply");
  accepted(cli, "binary PLY", "bin.ply");
  CHECK(write_ply("cut.ply", 0, 40)); // the last 4 faces (10 bytes a line)
  refused(cli, "ASCII PLY cut short", "cut.ply", "declares 12 'face' elements", "ends after 8", "truncated");
  CHECK(write_ply("cutbin.ply", 1, 20));
  refused(cli, "binary PLY cut short", "cutbin.ply", "binary PLY", "ends after 10", "truncated");
  CHECK(fixture_write(dir, "header.ply", "ply\nformat ascii 1.0\nelement vertex eight\nend_header\n"));
  refused(cli, "PLY header garbled", "header.ply", "PLY header line 3", "element NAME COUNT", 0);

  // face indices out of range: refused, not clamped or dropped
  CHECK(write_off("b.off", NULL, 12) && write_obj("box.obj", NULL, 0) && write_gltf("b.gltf", -1));
  accepted(cli, "OFF", "b.off");
  accepted(cli, "OBJ", "box.obj");
  accepted(cli, "glTF", "b.gltf");
  static const char *const off_bad[] = {"8", "-1", "4294967296", "99999", "x"};
  for (int k = 0; k < 5; ++k) {
    CHECK(write_off("bad.off", off_bad[k], 12));
    refused(cli, "OFF face index out of range", "bad.off", "bad.off", "face 5", off_bad[k]);
  }
  CHECK(write_off("bad.off", NULL, 13));
  refused(cli, "OFF with fewer faces than declared", "bad.off", "bad.off", "12 faces of the 13", 0);
  CHECK(write_gltf("bad.gltf", 8) && write_gltf("big.gltf", 60000));
  refused(cli, "glTF index = vertex count", "bad.gltf", "bad.gltf", "out-of-range", 0);
  refused(cli, "glTF index far past the vertices", "big.gltf", "big.gltf", "out-of-range", 0);
  static const struct {
    const char *line;
    size_t size;
  } obj_bad[] = {{"f 1 3\0 4", 9}, {"f\0 1 3 4", 9}, {"\0f 1 3 4", 9}, {"f 1 3 4\0", 9}, {"f 1 0 4", 7},
                 {"f 1 9 4", 7},    {"f 1 -9 4", 8},  {"f 1 99999999999 4", 17}};
  for (size_t k = 0; k < sizeof obj_bad / sizeof obj_bad[0]; ++k) {
    CHECK(write_obj("bad.obj", obj_bad[k].line, obj_bad[k].size));
    refused(cli, "OBJ face line damaged", "bad.obj", "bad.obj", 0, 0);
  }

  static const char *const files[] = {"b.off", "box.obj", "b.gltf", "bad.off", "bad.gltf", "big.gltf", "bad.obj", "a.obj", "b.stl", "bin.stl", "solid.STL", "noend.stl", "cut.stl",
                                      "garbled.stl", "short.stl", "long.stl", "solidshort.stl", "tiny.stl",
                                      "pipe.obj", "b.ply", "bin.ply", "cut.ply", "cutbin.ply", "header.ply", "big.json", "scene.json", "model.h5", "stderr.txt", NULL};
  rmdir(sub);
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
