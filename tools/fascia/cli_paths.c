// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The check every command makes of its file arguments before any work: each
// input that exists is a regular file (a FIFO would block the reader
// forever, a device or folder is no input); each output can be written (its
// folder exists, is a folder, is writable; the path is not a link, FIFO,
// device or folder that a rename would replace); no output is one of the
// inputs or another output (compared by file identity, device and inode, not
// by spelling), including the files an output folder will hold by pattern
// (`<organ>-<k>.vtp`); and temporary files that a killed fascia left next to
// the outputs are removed.
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fnmatch.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "commands.h"
#include "fascia/files.h"

#define PATH_TEXT 4096

// What names a file, existing or not: an existing file by device and inode;
// one still to be made by its folder's device and inode and its name there.
typedef struct file_key {
  int exists;
  dev_t dev;
  ino_t ino;
  const char *name; ///< exists == 0: the last component of the path
} file_key;

static const char *folder_of(const char *path, char *out) { return fascia_path_folder(path, out, PATH_TEXT); }

static int same_key(const file_key *a, const file_key *b) {
  if (a->exists != b->exists || a->dev != b->dev || a->ino != b->ino) return 0;
  return a->exists || !strcmp(a->name, b->name);
}

static int refuse(const char *command, int status, const char *format, const char *a, const char *b, const char *c) {
  fprintf(stderr, "fascia %s: ", command);
  fprintf(stderr, format, a, b, c);
  fputc('\n', stderr);
  return status;
}

// The folder that will hold `path` exists, is a folder, and can be written.
static int check_folder(const char *command, const cli_path *p, const char *path) {
  char folder[PATH_TEXT];
  folder_of(path, folder);
  struct stat st;
  if (stat(folder, &st) != 0)
    return refuse(command, 1, "%s '%s': folder '%s' does not exist; create it first", p->option, path, folder);
  if (!S_ISDIR(st.st_mode))
    return refuse(command, 1, "%s '%s': '%s' is not a folder", p->option, path, folder);
  if (access(folder, W_OK | X_OK) != 0)
    return refuse(command, 1, "%s '%s': cannot write in folder '%s' (permission denied)", p->option, path, folder);
  return -1;
}

// An output file: refused when a rename would replace something that is not
// a regular file; *key says which file it names.
static int check_output_file(const char *command, const cli_path *p, const char *path, file_key *key) {
  int rc = check_folder(command, p, path);
  if (rc >= 0) return rc;
  struct stat st;
  if (lstat(path, &st) == 0) {
    if (!S_ISREG(st.st_mode))
      return refuse(command, 2, "%s '%s' is %s; give the path of a regular file (it would be replaced by one)",
                    p->option, path, fascia_file_kind(st.st_mode));
    key->exists = 1, key->dev = st.st_dev, key->ino = st.st_ino, key->name = NULL;
    return -1;
  }
  char folder[PATH_TEXT];
  folder_of(path, folder);
  if (stat(folder, &st) != 0) return refuse(command, 1, "%s '%s': folder '%s' does not exist", p->option, path, folder);
  const char *slash = strrchr(path, '/');
  key->exists = 0, key->dev = st.st_dev, key->ino = st.st_ino, key->name = slash ? slash + 1 : path;
  return -1;
}

// An output folder: a folder (or a name its parent lets us create).
static int check_output_dir(const char *command, const cli_path *p) {
  struct stat st;
  if (stat(p->path, &st) != 0) return check_folder(command, p, p->path); // made by the command
  if (!S_ISDIR(st.st_mode))
    return refuse(command, 2, "%s '%s' is %s, not a folder", p->option, p->path, fascia_file_kind(st.st_mode));
  if (access(p->path, W_OK | X_OK) != 0)
    return refuse(command, 1, "%s '%s': cannot write in this folder (permission denied)%s", p->option, p->path, "");
  return -1;
}

// An input that exists must be a regular file (stat follows links: a link
// to a file is fine); exit 1, as when its reader refuses it. One that does
// not exist is left to its reader, which says so with the reason.
static int check_input(const char *command, const cli_path *p) {
  struct stat st;
  if (stat(p->path, &st) != 0 || S_ISREG(st.st_mode)) return -1;
  return refuse(command, 1, "%s '%s' is %s, not a regular file; give the path of the file itself", p->option, p->path,
                fascia_file_kind(st.st_mode));
}

// An input, or another output file, that lies in output folder p and whose
// name matches one of the folder's patterns would be replaced by (or would
// replace) the files written there.
static int check_folder_patterns(const char *command, const cli_path *paths, int count, const cli_path *p) {
  struct stat dir;
  if (!p->names || stat(p->path, &dir) != 0) return -1; // a folder still to be made holds nothing yet
  for (int j = 0; j < count; ++j) {
    const cli_path *other = paths + j;
    if (other == p || other->kind == CLI_OUTPUT_DIR || !other->path || !other->path[0]) continue;
    char folder[PATH_TEXT];
    struct stat st;
    if (stat(folder_of(other->path, folder), &st) != 0 || st.st_dev != dir.st_dev || st.st_ino != dir.st_ino)
      continue;
    const char *slash = strrchr(other->path, '/');
    const char *name = slash ? slash + 1 : other->path;
    for (int n = 0; p->names[n]; ++n)
      if (!fnmatch(p->names[n], name, 0)) {
        char what[2 * PATH_TEXT];
        snprintf(what, sizeof what, "'%s' writes files named '%s' there, and %s '%s'", p->path, p->names[n],
                 other->option, other->path);
        return refuse(command, 2, "%s %s is one of them: %s; give another folder", p->option, what,
                      other->kind == CLI_INPUT ? "writing would destroy that input"
                                               : "one output would overwrite the other");
      }
  }
  return -1;
}

// Refuses output key k (named option, path) when it is an input or an
// earlier output.
static int check_distinct(const char *command, const cli_path *paths, int count, int self, const char *path,
                          const file_key *key, const file_key *keys, const char *const *key_paths, int key_count) {
  for (int j = 0; j < count; ++j) {
    const cli_path *in = paths + j;
    if (in->kind != CLI_INPUT || !in->path || !in->path[0]) continue;
    if (paths[self].may_be && !strcmp(paths[self].may_be, in->option)) continue;
    struct stat st;
    if (!key->exists || stat(in->path, &st) != 0) continue;
    if (st.st_dev == key->dev && st.st_ino == key->ino) {
      char what[PATH_TEXT + 64];
      snprintf(what, sizeof what, "%s '%s'", in->option, in->path);
      return refuse(command, 2, "%s '%s' is the same file as the %s: writing it would destroy that input; give "
                                "another output path",
                    paths[self].option, path, what);
    }
  }
  for (int k = 0; k < key_count; ++k)
    if (same_key(key, keys + k))
      return refuse(command, 2, "%s and %s name the same file ('%s'): one would overwrite the other",
                    paths[self].option, key_paths[k], path);
  return -1;
}

#define MAX_KEYS 64

int cli_check_paths(const char *command, const cli_path *paths, int count) {
  file_key keys[MAX_KEYS];
  const char *key_options[MAX_KEYS];
  char joined[MAX_KEYS][PATH_TEXT];
  int key_count = 0;
  for (int k = 0; k < count; ++k) {
    const cli_path *p = paths + k;
    if (p->kind == CLI_INPUT && p->path && p->path[0]) {
      const int rc = check_input(command, p);
      if (rc >= 0) return rc;
    }
  }
  for (int k = 0; k < count; ++k) {
    const cli_path *p = paths + k;
    if (p->kind == CLI_INPUT || !p->path) continue;
    if (!p->path[0]) return refuse(command, 2, "%s needs a path, found an empty one%s%s", p->option, "", "");
    if (p->kind == CLI_OUTPUT_DIR) {
      int rc = check_output_dir(command, p);
      if (rc < 0) rc = check_folder_patterns(command, paths, count, p);
      if (rc >= 0) return rc;
      // the folder itself, when it is still to be made, against the other outputs (-o X --paraview X)
      struct stat st;
      if (stat(p->path, &st) != 0 && key_count < MAX_KEYS) {
        file_key key;
        snprintf(joined[key_count], PATH_TEXT, "%s", p->path);
        rc = check_output_file(command, p, joined[key_count], &key);
        if (rc < 0) rc = check_distinct(command, paths, count, k, joined[key_count], &key, keys, key_options, key_count);
        if (rc >= 0) return rc;
        keys[key_count] = key;
        key_options[key_count++] = p->option;
      }
    }
    // the files themselves: the path, or the names an output folder will hold
    for (int n = 0; p->kind == CLI_OUTPUT_FILE ? n < 1 : p->names && p->names[n]; ++n) {
      if (key_count == MAX_KEYS) break;
      char *path = joined[key_count];
      if (p->kind == CLI_OUTPUT_FILE) snprintf(path, PATH_TEXT, "%s", p->path);
      else snprintf(path, PATH_TEXT, "%s/%s", p->path, p->names[n]);
      struct stat st;
      if (p->kind == CLI_OUTPUT_DIR && stat(p->path, &st) != 0) continue; // a new folder holds nothing yet
      if (p->kind == CLI_OUTPUT_DIR && strpbrk(p->names[n], "*?[")) continue; // a pattern: check_folder_patterns
      file_key key;
      int rc = check_output_file(command, p, path, &key);
      if (rc < 0) rc = check_distinct(command, paths, count, k, path, &key, keys, key_options, key_count);
      if (rc >= 0) return rc;
      keys[key_count] = key;
      key_options[key_count++] = p->option;
    }
  }
  // the outputs are sound: now their leftovers from killed runs can go
  int removed = 0;
  for (int k = 0; k < count; ++k) {
    const cli_path *p = paths + k;
    if (p->kind == CLI_OUTPUT_FILE && p->path) removed += fascia_file_remove_stale(p->path);
    if (p->kind == CLI_OUTPUT_DIR && p->path) removed += fascia_file_remove_stale_in(p->path);
  }
  if (removed)
    fprintf(stderr, "fascia %s: removed %d temporary file%s ('*.tmp-PID-K') that an interrupted fascia left behind\n",
            command, removed, removed == 1 ? "" : "s");
  return -1;
}
