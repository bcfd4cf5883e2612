/* Small dense linear algebra: the normal equations of the program's little least-squares
 * fits (a few unknowns, solved where they are built). */
#ifndef WOVEN_LINALG_H
#define WOVEN_LINALG_H

/* Solves the symmetric positive definite n x n system m x = b in place (Cholesky; m, row
 * major, is overwritten, b becomes x). Returns 0 when m is not positive definite. */
int wv_solve_spd(double *m, double *b, int n);

#endif
