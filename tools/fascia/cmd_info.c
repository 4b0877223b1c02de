// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia info`: version, build options and which parts were built.
#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "fascia/fascia.h"

int cmd_info(int argc, char **argv) {
  for (int k = 1; k < argc; ++k)
    if (!strcmp(argv[k], "--help")) {
      printf("usage: fascia info\n");
      return 0;
    } else if (strcmp(argv[k], "--verbose")) {
      fprintf(stderr, "fascia info: unknown option '%s'\n", argv[k]);
      return 2;
    }
  printf("fascia %s\n", fascia_version());
  fascia_ctx *ctx = cli_ctx(0, 0);
  printf("threads: %d\n", fascia_ctx_threads(ctx));
  fascia_ctx_destroy(&ctx);
  return 0;
}
