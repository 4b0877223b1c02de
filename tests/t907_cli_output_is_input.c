// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// An output path that names an input (or another output) is refused before
// any work, with exit status 2 and one line naming both options, and the
// input is left byte for byte as it was: `run M -o M`, `--checkpoint M`,
// `--history M`, a hard link or another spelling of M, `-o X --checkpoint
// X`, `--snapshots` holding M under one of its names; `prep S -o S` and `-o`
// naming one of the scene's meshes. A symbolic link, FIFO or device given as
// an output is refused too instead of being replaced by a regular file.
// Output folders are checked by the names they write by pattern too: a model
// named like a per-step ParaView file in the --paraview folder, a mesh named
// like a preview part in the --preview folder; an output folder and an
// output file of one name (-o P --paraview P); the scene's label table as
// the --labelmap's table. An input that is a FIFO, device or folder (the
// model, --resume, --drive, inspect's model) is refused at once instead of
// blocking the reader.
// Continuing a checkpoint into the same file (--resume C --checkpoint C)
// stays allowed.
// Usage: t907_cli_output_is_input PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;
static char original[CLI_TEXT_SIZE], now[CLI_TEXT_SIZE];

// Runs `command`: exit `status`, one line containing `expect`, and `keep`
// unchanged (its bytes as `original` holds them, `length` of them).
static int refused_with(int status, const char *command, const char *expect, const char *keep, long length) {
  CHECK(cli_shell(command, &result));
  const long n = cli_read_file(keep, now, sizeof now);
  const int same = n == length && !memcmp(now, original, (size_t)length);
  if (result.status != status || cli_lines(result.err) != 1 || !strstr(result.err, expect) || !same) {
    fprintf(stderr, "%s\n  exit %d, %s %s, stderr:\n%.800s\n", command, result.status, keep,
            same ? "unchanged" : "CHANGED", result.err);
    return 1;
  }
  return 0;
}

// The same with exit 2: a path given wrongly.
static int refused(const char *command, const char *expect, const char *keep, long length) {
  return refused_with(2, command, expect, keep, length);
}

// Runs `command`: exit 2 and `path` is still what it was: a symbolic link
// ('l'), FIFO ('p') or character device ('c').
static int kept(const char *command, const char *path, char kind) {
  CHECK(cli_shell(command, &result));
  struct stat st;
  const int found = lstat(path, &st) == 0;
  const int same = found && (kind == 'l'   ? S_ISLNK(st.st_mode)
                             : kind == 'p' ? S_ISFIFO(st.st_mode)
                                           : S_ISCHR(st.st_mode));
  if (result.status != 2 || cli_lines(result.err) != 1 || !same) {
    fprintf(stderr, "%s\n  exit %d, %s %s, stderr:\n%.800s\n", command, result.status, path,
            same ? "kept" : "REPLACED", result.err);
    return 1;
  }
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t907_cli_output_is_input PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char dir[512], model[1024], err[1024], command[8192], path[1024], other[1024], args[2048];
  snprintf(dir, sizeof dir, "%s/t907", argv[2]);
  snprintf(model, sizeof model, "%s/v.h5", dir);
  snprintf(err, sizeof err, "%s/t907_stderr.txt", argv[2]);
  snprintf(command, sizeof command, "rm -rf '%s' && mkdir -p '%s/snap'", dir, dir);
  CHECK(system(command) == 0);
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  const long length = cli_read_file(model, original, sizeof original);
  CHECK(length > 0);

  int failures = 0;
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s'", fascia, model, model);
  failures += refused(command, "-o", model, length);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --checkpoint '%s'", fascia, model, model);
  failures += refused(command, "--checkpoint", model, length);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --history '%s'", fascia, model, model);
  failures += refused(command, "--history", model, length);
  snprintf(command, sizeof command, "'%s' run '%s' --static -o '%s'", fascia, model, model);
  failures += refused(command, "-o", model, length);
  // the same file spelled another way, and under another name (a hard link)
  snprintf(command, sizeof command, "cd '%s' && '%s' run ./v.h5 --steps 2 -o ../t907/snap/../v.h5", dir, fascia);
  failures += refused(command, "-o", model, length);
  snprintf(path, sizeof path, "%s/hard.h5", dir);
  CHECK(link(model, path) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s'", fascia, model, path);
  failures += refused(command, "-o", model, length);
  // an output folder holding the model under one of the names it writes
  snprintf(path, sizeof path, "%s/snap/tissue-final.csv", dir);
  CHECK(link(model, path) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --snapshots '%s/snap'", fascia, path, dir);
  failures += refused(command, "--snapshots", model, length);
  // two outputs on one file: the checkpoint would be lost
  snprintf(path, sizeof path, "%s/r.h5", dir);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s' --checkpoint '%s'", fascia, model, path, path);
  failures += refused(command, "the same file", model, length);
  CHECK(!cli_file_exists(path));

  // links, FIFOs and devices are not replaced by a regular file
  snprintf(path, sizeof path, "%s/link.h5", dir);
  snprintf(other, sizeof other, "%s/target.h5", dir);
  CHECK(symlink(other, path) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s'", fascia, model, path);
  failures += kept(command, path, 'l');
  snprintf(command, sizeof command, "'%s' beam --frames 6x2x2 -o '%s'", fascia, path);
  failures += kept(command, path, 'l');
  snprintf(path, sizeof path, "%s/fifo", dir);
  CHECK(mkfifo(path, 0666) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --checkpoint '%s'", fascia, model, path);
  failures += kept(command, path, 'p');
  snprintf(path, sizeof path, "%s/null", dir);
  snprintf(command, sizeof command, "mknod '%s' c 1 3 2>/dev/null", path);
  if (system(command) == 0) {
    snprintf(command, sizeof command, "'%s' run '%s' --static -o '%s'", fascia, model, path);
    failures += kept(command, path, 'c');
  } else {
    fprintf(stderr, "t907: the device case is skipped: mknod needs root\n");
  }

  // an input named like the files an output folder writes per step
  snprintf(path, sizeof path, "%s/pv", dir);
  CHECK(mkdir(path, 0777) == 0);
  snprintf(path, sizeof path, "%s/pv/b-0000.vtp", dir);
  CHECK(link(model, path) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --paraview '%s/pv'", fascia, path, dir);
  failures += refused(command, "--paraview", model, length);
  // another output named like the per-step files of an output folder
  snprintf(path, sizeof path, "%s/pv/c-0001.vtu", dir);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --paraview '%s/pv' --checkpoint '%s'", fascia, model,
           dir, path);
  failures += refused(command, "--checkpoint", model, length);
  CHECK(!cli_file_exists(path));
  // an output folder still to be made and an output file of the same name
  snprintf(path, sizeof path, "%s/P.h5", dir);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s' --paraview '%s'", fascia, model, path, path);
  failures += refused(command, "--paraview", model, length);
  CHECK(!cli_file_exists(path));
  // inputs that are not regular files: refused at once, never read (a FIFO blocks its reader)
  snprintf(path, sizeof path, "%s/in-fifo", dir);
  CHECK(mkfifo(path, 0666) == 0);
  static const char *const fifo_inputs[] = {"run '%s' --steps 2", "run '%2$s' --steps 2 --resume '%1$s'",
                                            "run '%2$s' --steps 2 --drive A='%1$s'", "inspect '%s'",
                                            "run '%2$s' --steps 2 --drive A='%3$s'"};
  for (size_t k = 0; k < sizeof fifo_inputs / sizeof fifo_inputs[0]; ++k) {
    char line[2048];
    snprintf(line, sizeof line, fifo_inputs[k], path, model, dir); // the last one: a folder
    snprintf(command, sizeof command, "timeout 20 '%s' %s", fascia, line);
    failures += refused_with(1, command, k + 1 == sizeof fifo_inputs / sizeof fifo_inputs[0] ? "a folder" : "FIFO",
                             model, length);
  }

#ifdef FASCIA_HAVE_PREP
  { // a mesh named like a preview part, in the --preview folder
    char pdir[600], pscene[1024], pmesh[1024];
    snprintf(pdir, sizeof pdir, "%s/preview", dir);
    CHECK(mkdir(pdir, 0777) == 0);
    CHECK(cli_write_tiny_scene(pdir, pscene, pmesh));
    snprintf(path, sizeof path, "%s/A.vtp", pdir);
    CHECK(rename(pmesh, path) == 0);
    snprintf(command, sizeof command, "sed -i 's/a.obj/A.vtp/g' '%s'", pscene);
    CHECK(system(command) == 0);
    const long mesh_length = cli_read_file(path, original, sizeof original);
    snprintf(command, sizeof command, "'%s' prep '%s' -o '%s/p.h5' --preview '%s'", fascia, pscene, dir, pdir);
    failures += refused(command, "--preview", path, mesh_length);
  }
  { // the scene's own label table as the table written beside --labelmap
    char ldir[600], lscene[1024], table[1024];
    snprintf(ldir, sizeof ldir, "%s/labels", dir);
    CHECK(mkdir(ldir, 0777) == 0);
    snprintf(table, sizeof table, "%s/X.tsv", ldir);
    FILE *f = fopen(table, "w");
    CHECK(f);
    fputs("1\tA\n2\tB\n", f);
    fclose(f);
    snprintf(path, sizeof path, "%s/X.nii.gz", ldir);
    f = fopen(path, "w");
    CHECK(f);
    fputs("not read: the paths are refused first\n", f);
    fclose(f);
    snprintf(lscene, sizeof lscene, "%s/s.json", ldir);
    f = fopen(lscene, "w");
    CHECK(f);
    fputs("{\"fascia_scene\": 1, \"voxel_size\": 0.02,\n"
          " \"segmentation\": {\"file\": \"X.nii.gz\", \"labels\": \"X.tsv\"},\n"
          " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
          " \"organs\": [{\"name\": \"A\", \"labels\": \"A\"}, {\"name\": \"B\", \"labels\": \"B\"}],\n"
          " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.1,\n"
          "  \"material\": \"soft\", \"frame_spacing\": 0.1, \"sample_spacing\": 0.05}]}\n",
          f);
    fclose(f);
    const long table_length = cli_read_file(table, original, sizeof original);
    snprintf(command, sizeof command, "'%s' prep '%s' -o '%s/l.h5' --labelmap '%s/X.nii'", fascia, lscene, dir, ldir);
    failures += refused(command, "segmentation.labels", table, table_length);
  }
  // prep: the scene or one of its meshes as the model file
  char scene[1024], mesh[1024];
  CHECK(cli_write_tiny_scene(dir, scene, mesh));
  const long scene_length = cli_read_file(scene, original, sizeof original);
  snprintf(command, sizeof command, "'%s' prep '%s' -o '%s'", fascia, scene, scene);
  failures += refused(command, "scene", scene, scene_length);
  const long mesh_length = cli_read_file(mesh, original, sizeof original);
  snprintf(command, sizeof command, "'%s' prep '%s' -o '%s'", fascia, scene, mesh);
  failures += refused(command, "mesh", mesh, mesh_length);
#endif
  CHECK(failures == 0);

  // continuing a checkpoint into the file it was read from is the normal use
  snprintf(path, sizeof path, "%s/c.h5", dir);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --checkpoint '%s'", fascia, model, path);
  CHECK(cli_shell(command, &result) && result.status == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 4 --resume '%s' --checkpoint '%s'", fascia, model, path,
           path);
  CHECK(cli_shell(command, &result) && result.status == 0);
  if (result.status != 0) fprintf(stderr, "%.800s\n", result.err);
  return CHECK_RESULT();
}
