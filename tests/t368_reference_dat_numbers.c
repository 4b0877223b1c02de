// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// CalculiX reads and writes numbers its own way, and the references must
// follow both:
//  - its Fortran E format drops the E of a three-digit exponent
//    ("1.234567-100"), which a C reader takes for 1.234567: a tiny reaction
//    would be read as a large one. Every reader of the references (the
//    block totals, a node's values, the cantilever's tip) goes through
//    fascia_ccx_dat_numbers;
//  - it reads 20 characters of a deck's field and cuts the rest without a
//    word: -7.61426191299358e-05 is read as -7.6. Every deck is checked
//    (fascia_ccx_deck_fits) before ccx runs it.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "beam_calculix.h"
#include "check.h"

static int close_to(double a, double b) { return fabs(a - b) <= 1e-12 * fabs(b); }

int main(void) {
  double v[3];
  // the usual form, and three-digit exponents without their E
  CHECK(fascia_ccx_dat_numbers("  1.000000E+00 -2.500000E-01  3.125000E+02\n", v, 3));
  CHECK(v[0] == 1 && v[1] == -0.25 && v[2] == 312.5);
  CHECK(fascia_ccx_dat_numbers(" 1.234567-100 -5.000000+101 0.000000E+00\n", v, 3));
  CHECK(close_to(v[0], 1.234567e-100) && close_to(v[1], -5e101) && v[2] == 0);
  // too few numbers: refused, not half read
  CHECK(!fascia_ccx_dat_numbers(" 1.0 2.0\n", v, 3));
  // a block's total after blank lines, in either form
  CHECK(fascia_ccx_dat_triple("\n   \n  2.000000-101  1.000000E+00 -1.000000E+00\n", v));
  CHECK(close_to(v[0], 2e-101) && v[1] == 1 && v[2] == -1);
  // a node's values in a block, the block ending at the first other line
  const char *block = "\n     7  1.000000E-03  2.000000-102 -3.000000E-03\n"
                      "    12  4.000000E-03 -5.000000-104  6.000000E-03\n"
                      " total force\n    99  1 2 3\n";
  CHECK(fascia_ccx_dat_node(block, 12, v));
  CHECK(v[0] == 4e-3 && close_to(v[1], -5e-104) && v[2] == 6e-3);
  CHECK(fascia_ccx_dat_node(block, 7, v) && close_to(v[1], 2e-102));
  CHECK(!fascia_ccx_dat_node(block, 99, v)); // past the block's end
  CHECK(!fascia_ccx_dat_node(NULL, 7, v));
  // decks: a 21-character field is refused with its line; a heading's text,
  // keywords and comments are not fields
  const char *tmp = getenv("TMPDIR");
  char path[1024], why[256];
  snprintf(path, sizeof path, "%s/t368-%d.inp", tmp && tmp[0] ? tmp : "/tmp", (int)getpid());
  FILE *f = fopen(path, "w");
  CHECK(f != NULL);
  if (f) {
    fputs("*HEADING\nthe demo tissue against CalculiX, a long heading line\n** a comment, of any length at all\n"
          "*NODE, NSET=NALL\n1, -7.614261912994e-05, 0.5, 1.25\n", f);
    fclose(f);
  }
  CHECK(fascia_ccx_deck_fits(path, why, sizeof why));
  f = fopen(path, "a");
  if (f) {
    fputs("2, -7.61426191299358e-05, 0.5, 1.25\n", f);
    fclose(f);
  }
  CHECK(!fascia_ccx_deck_fits(path, why, sizeof why) && strstr(why, "line 6") && strstr(why, "21 characters"));
  printf("t368: refused: %s\n", why);
  remove(path);
  CHECK(!fascia_ccx_deck_fits(path, why, sizeof why)); // gone: cannot read it
  printf("t368: CalculiX's numbers read with and without the E of their exponent; decks' fields fit\n");
  return CHECK_RESULT();
}
