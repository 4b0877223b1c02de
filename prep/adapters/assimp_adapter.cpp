// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// assimp adapter: every (node, triangle mesh) pair of a file becomes one part,
// with the node's accumulated transform applied, so that parts can be picked
// by node or mesh name in C.
#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cstdlib>
#include <cstring>
#include <exception>
#include <mutex>
#include <string>
#include <vector>

#include "adapters.h"

namespace {

// assimp's importers repair some damage and say so only in their log: an
// OFF index past the vertices is clamped, a glTF face with one is dropped,
// an OBJ face cut by a NUL is ignored. Its errors, and its warnings about
// faces dropped or indices out of range, reach the read that caused them
// (per thread) and refuse the file.
thread_local std::string *assimp_complaint = nullptr;

void keep_complaint(const char *message) {
  if (!assimp_complaint || !assimp_complaint->empty() || !message) return;
  std::string m(message);
  const size_t tag = m.find(','); // "Error, T0: " or "Warn,  T0: " before the text
  const size_t colon = tag < 8 ? m.find(": ", tag) : std::string::npos;
  if (colon != std::string::npos) m = m.substr(colon + 2);
  while (!m.empty() && (m.back() == '\n' || m.back() == '\r')) m.pop_back();
  for (char &c : m)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  *assimp_complaint = m.empty() ? std::string("an error without text") : m;
}

struct ErrorStream : Assimp::LogStream {
  void write(const char *message) override { keep_complaint(message); }
};

struct WarningStream : Assimp::LogStream {
  void write(const char *message) override {
    static const char *const damage[] = {"out-of-range", "out of range", "dropped", "Ignoring", "ignoring",
                                         "Skipping face", "skipping face", "invalid index", "Invalid index"};
    for (const char *d : damage)
      if (message && std::strstr(message, d)) {
        keep_complaint(message);
        return;
      }
  }
};

void listen_to_assimp() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!Assimp::DefaultLogger::isNullLogger()) return; // the application has its own: leave it
    Assimp::Logger *log = Assimp::DefaultLogger::create(nullptr, Assimp::Logger::NORMAL, 0);
    log->attachStream(new ErrorStream, Assimp::Logger::Err);
    log->attachStream(new WarningStream, Assimp::Logger::Warn);
  });
}

struct Collected {
  std::vector<std::string> node_names, mesh_names;
  std::vector<int32_t> vertex_offset{0}, triangle_offset{0};
  std::vector<double> vertices;
  std::vector<int32_t> triangles;
  int32_t skipped = 0;
};

void collect(const aiScene *scene, const aiNode *node, const aiMatrix4x4 &parent, Collected &c) {
  const aiMatrix4x4 m = parent * node->mTransformation;
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    const aiMesh *mesh = scene->mMeshes[node->mMeshes[k]];
    const int32_t base = c.vertex_offset.back();
    int32_t tris = 0;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace &face = mesh->mFaces[f];
      if (face.mNumIndices != 3) {
        ++c.skipped;
        continue;
      }
      for (int r = 0; r < 3; ++r) c.triangles.push_back(base + (int32_t)face.mIndices[r]);
      ++tris;
    }
    if (tris == 0 && mesh->mNumFaces > 0) continue; // a point or line set: not a surface
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D p = m * mesh->mVertices[v];
      c.vertices.push_back(p.x);
      c.vertices.push_back(p.y);
      c.vertices.push_back(p.z);
    }
    c.node_names.emplace_back(node->mName.C_Str());
    c.mesh_names.emplace_back(mesh->mName.C_Str());
    c.vertex_offset.push_back(base + (int32_t)mesh->mNumVertices);
    c.triangle_offset.push_back(c.triangle_offset.back() + tris);
  }
  for (unsigned k = 0; k < node->mNumChildren; ++k) collect(scene, node->mChildren[k], m, c);
}

char *dup(const std::string &s) {
  char *p = (char *)std::malloc(s.size() + 1);
  if (p) std::memcpy(p, s.c_str(), s.size() + 1);
  return p;
}

template <typename T> T *copy_out(const std::vector<T> &v) {
  T *p = (T *)std::malloc(v.empty() ? sizeof(T) : v.size() * sizeof(T));
  if (p && !v.empty()) std::memcpy(p, v.data(), v.size() * sizeof(T));
  return p;
}

} // namespace

extern "C" void fascia_assimp_free(fascia_assimp_file **file) {
  if (!file || !*file) return;
  fascia_assimp_file *f = *file;
  for (int32_t p = 0; p < f->part_count; ++p) {
    if (f->node_names) std::free(f->node_names[p]);
    if (f->mesh_names) std::free(f->mesh_names[p]);
  }
  std::free(f->node_names);
  std::free(f->mesh_names);
  std::free(f->vertex_offset);
  std::free(f->triangle_offset);
  std::free(f->vertices);
  std::free(f->triangles);
  std::free(f);
  *file = nullptr;
}

extern "C" fascia_status fascia_assimp_read(fascia_ctx *ctx, const char *path, fascia_assimp_file **out) {
  *out = nullptr;
  fascia_assimp_file *f = nullptr;
  std::string complaint;
  struct Listening { // the complaint pointer is cleared on every way out
    explicit Listening(std::string *c) { assimp_complaint = c; }
    ~Listening() { assimp_complaint = nullptr; }
  };
  try {
    listen_to_assimp();
    Listening listening(&complaint);
    Assimp::Importer importer;
    // no vertex joining here: the CGAL repair merges duplicates and reports it.
    // ValidateDataStructure runs first and refuses what the loader built from a
    // damaged file (indices past the vertices, empty faces): without it
    // assimp's Triangulate step aborts the process on such a scene (fuzz_mesh,
    // tests/fuzz/regressions/mesh/off-bad-face-abort).
    const aiScene *scene = importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate);
    if (!scene || !scene->mRootNode) {
      const char *why = importer.GetErrorString();
      if (std::strstr(why, "contains no faces")) // points only, as validation says it
        return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                               "mesh '%s' has no triangles (assimp: %s); give a file with a surface mesh", path, why);
      return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                             "mesh '%s': cannot be read as a mesh (assimp: %s); check the file and its format", path,
                             why);
    }
    if (!complaint.empty())
      return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                             "mesh '%s': damaged, assimp read it only by changing it (assimp: %s); repair or export "
                             "the file again",
                             path, complaint.c_str());
    Collected c;
    collect(scene, scene->mRootNode, aiMatrix4x4(), c);
    f = (fascia_assimp_file *)std::calloc(1, sizeof *f);
    if (!f) throw std::bad_alloc();
    f->part_count = (int32_t)c.node_names.size();
    f->skipped_primitives = c.skipped;
    f->node_names = (char **)std::calloc(c.node_names.size() + 1, sizeof(char *));
    f->mesh_names = (char **)std::calloc(c.node_names.size() + 1, sizeof(char *));
    if (!f->node_names || !f->mesh_names) throw std::bad_alloc();
    for (size_t p = 0; p < c.node_names.size(); ++p) {
      f->node_names[p] = dup(c.node_names[p]);
      f->mesh_names[p] = dup(c.mesh_names[p]);
      if (!f->node_names[p] || !f->mesh_names[p]) throw std::bad_alloc();
    }
    f->vertex_offset = copy_out(c.vertex_offset);
    f->triangle_offset = copy_out(c.triangle_offset);
    f->vertices = copy_out(c.vertices);
    f->triangles = copy_out(c.triangles);
    if (!f->vertex_offset || !f->triangle_offset || !f->vertices || !f->triangles) throw std::bad_alloc();
    *out = f;
    return FASCIA_OK;
  } catch (const std::bad_alloc &) {
    fascia_assimp_free(&f);
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "mesh '%s': out of memory while reading",
                           path);
  } catch (const std::exception &e) {
    fascia_assimp_free(&f);
    return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__, "mesh '%s': assimp failed: %s", path,
                           e.what());
  } catch (...) {
    fascia_assimp_free(&f);
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "mesh '%s': assimp: unknown exception",
                           path);
  }
}
