/* ncperf's C kernels: the feed profile's rounds (core/engine/profile.py), move by move.
 *
 * A plain C library (no Python API), built by `pip install` where a C compiler is found
 * (pyproject.toml: an optional extension) and loaded with ctypes by core/model/native.py;
 * where it is absent numpy's code runs. ctypes lets go of the GIL while a kernel runs, so
 * the rounds' two directions run side by side on two cores.
 *
 * Every kernel does, for each element, the same IEEE-754 operations in the same order as
 * the numpy code it stands in for (named above each), so both give the same bits
 * (tests/test_native.py): built without fused multiply-adds (-ffp-contract=off) and
 * without fast-math; numpy's NaN rules for minimum and maximum (vmin, vmax); only +, -,
 * *, / and sqrt, which IEEE-754 rounds exactly (no transcendental: those stay numpy's).
 * They are the numba kernels of core/model/compiled.py written once more in C, which loads
 * in a millisecond where numba takes 0.4 s (issue 13).
 *
 * Arrays: double (float64), int8_t (int8), uint8_t (numpy's bool: 0 or 1), int64_t
 * (intp on 64-bit platforms; core/model/native.py loads the library only there).
 */

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#if defined(_WIN32)
#define EXPORT __declspec(dllexport)
#else
#define EXPORT __attribute__((visibility("default")))
#endif

/* np.maximum of two doubles: NaN if either is; the second of two equal values (numpy's
   vector loops take the CPU's max, which returns its second operand for +0.0 and -0.0). */
static inline double vmax(double a, double b) {
    if (a != a) return a;
    if (b != b) return b;
    return a > b ? a : b;
}

/* np.minimum of two doubles: NaN if either is; the second of two equal values. */
static inline double vmin(double a, double b) {
    if (a != a) return a;
    if (b != b) return b;
    return a < b ? a : b;
}

/* The version of this interface: core/model/native.py loads a library of its own
   version only (a stale build beside newer Python code is not used). */
EXPORT int64_t ncperf_kernels_version(void) { return 8; }

/* core.engine.profile._Rounds._all_marks (every != 0: the moves first..first+count-1) or
   _marks_of of the moves at[first..first+count-1] (two threads take a half each): each move's peak, whether it accelerates (rise) or brakes
   (fall), and through_*[k + 1]: move k accelerates to its very end or brakes from its
   very start. v has one more element than the moves. (Branches where numpy's code has
   masks: measured faster than computing every value and selecting, 4.9 against 6.4 ms
   on stellabee1's 169k moves.) */
EXPORT void marks(const int64_t *at, int64_t first, int64_t count, int every, const double *v,
                  const double *a_up, const double *a_dn, const double *between,
                  const double *cap, double rel_equal, double nil_distance, double *peak,
                  uint8_t *rise, uint8_t *fall, uint8_t *through_up, uint8_t *through_dn) {
    for (int64_t i = first; i < first + count; i++) {
        int64_t k = every ? i : at[i];
        double v0 = v[k], v1 = v[k + 1], au = a_up[k], ad = a_dn[k], lk = between[k];
        double q0 = v0 * v0;
        double q1 = v1 * v1;
        /* the peak: (2 L + v0^2 / a_up + v1^2 / a_dn) / (1/a_up + 1/a_dn) */
        double pk = q0 / au + lk * 2.0 + q1 / ad;
        pk = pk / (1.0 / au + 1.0 / ad);
        pk = vmax(vmin(cap[k], sqrt(vmax(pk, 0.0))), vmax(v0, v1));
        double t = vmax(pk, 1.0) * rel_equal;
        int r = pk > v0 + t;
        int f = pk > v1 + t;
        peak[k] = pk;
        rise[k] = (uint8_t)r;
        fall[k] = (uint8_t)f;
        int flat = 0;
        if (r != f) { /* the cruise length of a move that only accelerates or only brakes */
            double pk2 = pk * pk;
            double d_cr = lk - (pk2 - q0) / (2.0 * au);
            d_cr = d_cr - (pk2 - q1) / (2.0 * ad);
            flat = vmax(d_cr, 0.0) <= nil_distance;
        }
        through_up[k + 1] = (uint8_t)(r && flat);
        through_dn[k + 1] = (uint8_t)(f && flat);
    }
}

/* The speed at the ramp's upper end of move k (rising: its end, falling: its start): the
   next (previous) move's boundary speed where it ramps through, else its peak. */
static inline double upper_of(int rising, int64_t k, const uint8_t *through, const double *v0,
                              const double *v1, const double *peak) {
    return through[k + 1] ? (rising ? v1[k] : v0[k]) : peak[k];
}

/* core.engine.profile._chain_dv into dv, in one pass: each run of moves where a move
   continues the chain of the one before (rising: it accelerates through its start,
   through[k] and phase[k]; falling: it and the one before brake, through[k + 1]) gets the
   speed change from the chain's first move to its last; a move alone its own. */
static void chain_dv(int rising, int64_t n, const uint8_t *phase, const uint8_t *through,
                     const double *v0, const double *v1, const double *peak, double *dv) {
    int64_t k = 0;
    while (k < n) {
        int64_t first = k;
        if (rising)
            while (k + 1 < n && through[k + 1] && phase[k + 1]) k++;
        else
            while (k + 1 < n && through[k + 2] && phase[k + 1] && phase[k]) k++;
        int64_t last = k;
        double hi = rising ? upper_of(rising, last, through, v0, v1, peak) - v0[first]
                           : upper_of(rising, first, through, v0, v1, peak) - v1[last];
        for (int64_t m = first; m <= last; m++) dv[m] = hi;
        k++;
    }
}

/* core.engine.profile._Rounds._dense: the accelerations a and their off (a != acc) and
   term (the passes' terms) updated in place, this round's step and moved written; the
   largest relative change into *change, whether the terms are still plain into *finite;
   the moves the damping held back into behind, their targets into wanted (n each at
   most): returns how many. numpy's code writes off and term again over every piece of
   moves where one moved; here only the moves that moved are written: the others' are the
   same values already (off is a != acc and term the pass term of a wherever they are
   made, and each term was checked for finite when it was made). work: n doubles (the
   ramps' speed changes); aj and lim: acc / jerk and acc * acc / jerk, which do not change
   from round to round (the same quotients, made once by numpy). */
EXPORT int64_t dense_round(int rising, int64_t n, const uint8_t *phase, const uint8_t *through,
                           const double *v0, const double *v1, const double *peak, double *a,
                           const int8_t *last, double *term, uint8_t *off, const double *acc,
                           const double *jerk, const double *between, int8_t *step,
                           uint8_t *moved, double nil_speed, int *finite, double *change,
                           int64_t *behind, double *wanted, double *work, const double *aj,
                           const double *lim) {
    double *dv = work;
    chain_dv(rising, n, phase, through, v0, v1, peak, dv);
    int64_t n_behind = 0;
    double ch = 0.0;
    int fin = *finite;
    for (int64_t k = 0; k < n; k++) {
        double od = a[k];
        /* effective_acceleration(dv, acc, jerk, only=phase) */
        double d = dv[k], ak = acc[k], jk = jerk[k];
        double nw = ak;
        if (isfinite(jk) && d > nil_speed && phase[k]) {
            double t_full = d / ak + aj[k];
            double t_short = sqrt(d / jk) * 2.0;
            double t = d >= lim[k] ? t_full : t_short;
            nw = d / t;
        }
        /* the damping: the geometric mean where the step turns back */
        int8_t ls = last[k];
        double o = nw;
        if ((nw > od && ls < 0) || (nw < od && ls > 0)) {
            o = sqrt(od * nw);
            if (o != nw) {
                behind[n_behind] = k;
                wanted[n_behind] = nw;
                n_behind++;
            }
        }
        step[k] = (int8_t)((o > od ? 1 : 0) - (o < od ? 1 : 0));
        uint8_t mv = o != od;
        moved[k] = mv;
        if (mv) { /* (where o == od, o / od - 1 is 0 or NaN: no change either way) */
            double rel = fabs(o / od - 1.0);
            if (rel > ch) ch = rel; /* (NaN skipped, as nanmax) */
            a[k] = o;
            off[k] = o != acc[k];
            double tm = o * vmax(between[k], 0.0) * 2.0;
            term[k] = tm;
            if (!(isfinite(tm) && !(tm < 0.0))) fin = 0;
        }
    }
    *change = ch;
    *finite = fin;
    return n_behind;
}

/* core.engine.profile._passes_of with finite (no NaN, no -0.0, terms >= 0: fmin is a plain
   comparison and the clamp at 0 is left out), in three parts, the first two independent
   (two threads may take them side by side): the forward sums (w) and pass into out
   (passes_forward), the backward sums and pass into bwd (passes_backward: bwd[i] = the
   backward running minimum less the braking sum), then out = sqrt(min(out, bwd, b2))
   (passes_join). The sums sequential as np.cumsum's (the first term itself, then one term
   after the other), the minima running as np.fmin.accumulate's; an overflowed sum gives
   NaN in the join, np.minimum's rules. */
EXPORT void passes_forward(int64_t n1, const double *b2, const double *up, double *w,
                           double *out) {
    double wu = 0.0;
    double least = b2[0];
    for (int64_t i = 0; i < n1; i++) {
        if (i) wu = i == 1 ? up[0] : wu + up[i - 1];
        w[i] = wu;
        double x = b2[i] - wu;
        if (x < least) least = x;
        out[i] = least + wu;
    }
}

EXPORT void passes_backward(int64_t n1, const double *b2, const double *dn, double *bwd) {
    double wd = 0.0;
    for (int64_t i = 0; i < n1; i++) {
        if (i) wd = i == 1 ? dn[0] : wd + dn[i - 1];
        bwd[i] = wd;
    }
    double least = b2[n1 - 1] + bwd[n1 - 1];
    for (int64_t i = n1 - 1; i >= 0; i--) {
        double wd2 = bwd[i];
        double x = b2[i] + wd2;
        if (x < least) least = x;
        bwd[i] = least - wd2;
    }
}

EXPORT void passes_join(int64_t first, int64_t count, const double *b2, const double *bwd,
                        double *out) {
    for (int64_t i = first; i < first + count; i++)
        out[i] = sqrt(vmin(vmin(out[i], bwd[i]), b2[i]));
}

/* plugins.tangential._corner_feed_rows after its jerk column v_jerk ((m, 3) row-major:
   numpy's cube roots, which may be SIMD code of its own) for m corners (the plugin's
   pieces of corners run on two threads, each its own call): each corner's feed limits of
   the axes' speeds (max_feed / share_t), normal accelerations (sqrt(a_n R / share_n)) and
   jerks, inf where an axis has no share, NaN as 0 and -inf as the lowest double
   (np.nan_to_num), and the lowest of the nine with the first of equals (np.argmin). */
EXPORT void corner_limits(int64_t m, const double *share_t, const double *share_n,
                          const double *radius, const double *v_jerk, const double *max_feed,
                          const double *a_n, double *feed, int64_t *limit) {
    for (int64_t i = 0; i < m; i++) {
        double best = 0.0;
        int64_t at = 0;
        for (int c = 0; c < 9; c++) {
            int j = c % 3;
            double x;
            if (c < 3) {
                double s = share_t[3 * i + j];
                x = s > 0 ? max_feed[j] / s : INFINITY;
            } else if (c < 6) {
                double s = share_n[3 * i + j];
                x = s > 0 ? sqrt(a_n[j] * radius[i] / s) : INFINITY;
            } else {
                x = v_jerk[3 * i + j];
            }
            if (isnan(x))
                x = 0.0;
            else if (x == -INFINITY)
                x = -DBL_MAX;
            if (c == 0 || x < best) {
                best = x;
                at = c;
            }
        }
        feed[i] = best;
        limit[i] = at;
    }
}

/* Windows' linker wants the entry point of a Python extension, which setuptools builds
   this library as; nothing imports it (ctypes loads it). */
#if defined(_WIN32)
EXPORT void *PyInit__kernels(void) { return NULL; }
#endif
