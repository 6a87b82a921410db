/* Reference for the simulator benchmark: the closed loop of obsdesign.sim.kernel.run_loop
 * written as a plain C loop doing the same work per sample (plant with Heun substeps and
 * pre-sliding friction, exact observer recursion recomputed when the stiffness changes,
 * low-pass filter, PID with the observer's compensation, the drive's delay as the two rings of
 * the kernel (the controller's copy feeding the estimator, the plant's applying the command), the
 * plant's friction recorded, the nine output arrays of run_loop and its divergence stop).
 * Built with -O2 and called through ctypes by bench_sim.py, which also checks that its outputs
 * equal the numba kernel's. Not part of the package. */
#include <math.h>
#include <stddef.h>

#include "obsdesign_core.inc" /* obsdesign/export/c: friction branch, exact discretization */

/* The plant's value of the estimated state w3 (obsdesign.sim.kernel._true_friction). */
static double true_friction(double x, double v, double w, double dir, double xr, double fr, int model, int lag,
                            double Cf, double s, double sigma, double beta) {
    double fc;
    if (model) return w;
    fc = Cf * od_coulomb_n(x, dir, xr, fr, s);
    if (!lag) return fc;
    return fc + (beta > 0.0 ? w : sigma * v);
}

static void rhs(double x, double v, double w, double u, double dir, double xr, double fr, int model, int lag,
                double m, double Cf, double s, double sigma, double beta, double kappa, double *dv, double *dw) {
    if (model) {
        double k = od_stiffness(x, dir, xr, fr, Cf, s, kappa);
        if (lag) { *dv = (u - w) / m; *dw = (k + sigma / beta) * v; }
        else { *dv = (u - sigma * v - w) / m; *dw = k * v; }
        return;
    }
    double fc = Cf * od_coulomb_n(x, dir, xr, fr, s);
    if (beta > 0.0) { *dv = (u - fc - w) / m; *dw = (sigma * v - w) / beta; }
    else { *dv = (u - fc - sigma * v) / m; *dw = 0.0; }
}

long run_loop(long n_samples, double dt, long n_sub, int model, int lag, double m, double K, double G, double Cf,
              double s, double sigma, double beta, double kappa, const double *A0, const double *A1,
              const double *b0, const double *b1, const double *g0, const double *g1, double L1, double L2,
              int schedule, int controller, double kp, double ki, double kd, double tau_d, double u_max,
              const double *lp_phi, const double *lp_g0, const double *lp_g1, const double *x_ref,
              const double *u_open, const double *noise, double quant, long delay, double held,
              double *const *out) {
    /* out: x, x_meas, v, f, v_hat, f_hat, f_hat_filtered, u, stiffness (kernel.OUTPUT_NAMES) */
    double ring[delay > 0 ? delay : 1], ubuf[delay > 0 ? delay : 1];
    double h = dt / n_sub, x = 0, v = 0, w = 0;
    double pd = 0, pxr = 0, pfr = 0, ed = 0, exr = 0, efr = 0;
    double y1 = 0, y2 = 0, zf1 = 0, zf2 = 0, fh_prev = 0, xm_prev = 0, u_prev = 0;
    double integ = 0, deriv = 0, e_prev = 0, alpha = tau_d > 0 ? exp(-dt / tau_d) : 0.0;
    double k_coef = -1.0, c[12] = {0}, bu1 = 0, bu2 = 0, gx01 = 0, gx02 = 0, gx11 = 0, gx12 = 0, k_now = kappa;
    for (long i = 0; i < (delay > 0 ? delay : 1); i++) { ring[i] = held; ubuf[i] = held; }
    for (long n = 0; n < n_samples; n++) {
        double xm = x + noise[n];
        if (quant > 0.0) xm = quant * floor(xm / quant + 0.5);
        if (n == 0) { y1 = -L1 * xm; y2 = -L2 * xm; }
        else {
            double t1 = c[0] * y1 + c[1] * y2 + bu1 * u_prev + gx01 * xm_prev + gx11 * xm;
            double t2 = c[2] * y1 + c[3] * y2 + bu2 * u_prev + gx02 * xm_prev + gx12 * xm;
            y1 = t1; y2 = t2;
        }
        double vh = y1 + L1 * xm, fh = y2 + L2 * xm;
        if (n > 0) {
            double t1 = lp_phi[0] * zf1 + lp_phi[1] * zf2 + lp_g0[0] * fh_prev + lp_g1[0] * fh;
            double t2 = lp_phi[2] * zf1 + lp_phi[3] * zf2 + lp_g0[1] * fh_prev + lp_g1[1] * fh;
            zf1 = t1; zf2 = t2;
        }
        double ff = zf1;
        if (schedule == 0) { od_track(vh, xm, &ed, &exr, &efr, s); k_now = od_stiffness(xm, ed, exr, efr, Cf, s, kappa); }
        else if (schedule == 1) k_now = od_stiffness(x, pd, pxr, pfr, Cf, s, kappa);
        else k_now = kappa;
        if (k_now != k_coef) {
            k_coef = k_now;
            od_coefficients(A0[0] + k_now * A1[0], A0[1] + k_now * A1[1], A0[2] + k_now * A1[2], A0[3] + k_now * A1[3], dt, c);
            double bb1 = b0[0] + k_now * b1[0], bb2 = b0[1] + k_now * b1[1];
            double gg1 = g0[0] + k_now * g1[0], gg2 = g0[1] + k_now * g1[1];
            bu1 = c[4] * bb1 + c[5] * bb2; bu2 = c[6] * bb1 + c[7] * bb2;
            gx11 = c[8] * gg1 + c[9] * gg2; gx12 = c[10] * gg1 + c[11] * gg2;
            gx01 = c[4] * gg1 + c[5] * gg2 - gx11; gx02 = c[6] * gg1 + c[7] * gg2 - gx12;
        }
        double u_volt;
        if (controller == 0) u_volt = u_open[n] / K;
        else {
            double e = x_ref[n] - xm;
            if (n == 0) e_prev = e;
            deriv = alpha * deriv + (1.0 - alpha) * (e - e_prev) / dt;
            double integ_new = integ + e * dt;
            u_volt = kp * e + ki * integ_new + kd * deriv;
            if (controller == 2) u_volt += ff / K;
            if (fabs(u_volt + G / K) <= u_max) integ = integ_new;
            e_prev = e;
        }
        double total = u_volt + G / K;
        if (total > u_max) total = u_max; else if (total < -u_max) total = -u_max;
        double applied = total, drive = total;
        if (delay > 0) { /* the estimator's input and the plant's: the command of sample n - delay */
            long slot = n % delay;
            applied = ring[slot]; ring[slot] = total;
            drive = ubuf[slot]; ubuf[slot] = total;
        }
        double u_est = K * applied - G, u = K * drive - G;
        out[0][n] = x; out[1][n] = xm; out[2][n] = v;
        out[3][n] = true_friction(x, v, w, pd, pxr, pfr, model, lag, Cf, s, sigma, beta);
        out[4][n] = vh; out[5][n] = fh; out[6][n] = ff; out[7][n] = u; out[8][n] = k_now;
        if (!(fabs(x) < 1e3 && fabs(fh) < 1e12 && fabs(vh) < 1e12 && fabs(ff) < 1e12 && fabs(v) < 1e12)) return n + 1;
        for (long i = 0; i < n_sub; i++) {
            double k1v, k1w, k2v, k2w;
            rhs(x, v, w, u, pd, pxr, pfr, model, lag, m, Cf, s, sigma, beta, kappa, &k1v, &k1w);
            double xp = x + h * v, vp = v + h * k1v, wp = w + h * k1w;
            rhs(xp, vp, wp, u, pd, pxr, pfr, model, lag, m, Cf, s, sigma, beta, kappa, &k2v, &k2w);
            x += 0.5 * h * (v + vp); v += 0.5 * h * (k1v + k2v); w += 0.5 * h * (k1w + k2w);
            od_track(v, x, &pd, &pxr, &pfr, s);
        }
        fh_prev = fh; xm_prev = xm; u_prev = u_est;
    }
    return n_samples;
}
