/* The marker map's global bundle adjustment (Ceres Solver), the rigid fit
 * to control points and the rotation mean (Eigen). No Ceres or Eigen type
 * leaves this file: the face is mr_ba_* in track_internal.h. */
#include "track_internal.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Dense>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

/* Corner sigmas below this are taken as this (px): exact synthetic
 * corners would otherwise weigh the control points down to nothing. */
#define MR_BA_SIGMA_FLOOR_PX 0.02

namespace {

/* SIGINT/SIGTERM (mr_stop_requested) end the solve after the iteration
 * in progress. */
struct StopOnSignal : public ceres::IterationCallback {
    ceres::CallbackReturnType operator()(const ceres::IterationSummary &) override {
        return mr_stop_requested() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
    }
};

/* A solve's outcome: false with msg when a stop ended it (its callback
 * above) or its solution is not usable. */
bool solved(const ceres::Solver::Summary &sum, char *msg, size_t msg_size) {
    if (sum.termination_type == ceres::USER_FAILURE && mr_stop_requested()) {
        snprintf(msg, msg_size, "bundle adjustment interrupted at iteration %d; nothing written", (int)sum.iterations.size());
        return false;
    }
    if (!sum.IsSolutionUsable()) {
        snprintf(msg, msg_size, "bundle adjustment failed: %s", sum.message.c_str());
        return false;
    }
    return true;
}

/* Quaternion (w x y z) and translation of a row-major rigid 4x4. */
void split_pose(const double *m, double q[4], double t[3]) {
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) R(r, c) = m[4 * r + c];
    Eigen::Quaterniond e(R);
    e.normalize();
    q[0] = e.w();
    q[1] = e.x();
    q[2] = e.y();
    q[3] = e.z();
    for (int r = 0; r < 3; r++) t[r] = m[4 * r + 3];
}

void join_pose(const double q[4], const double t[3], double *m) {
    Eigen::Quaterniond e(q[0], q[1], q[2], q[3]);
    e.normalize();
    Eigen::Matrix3d R = e.toRotationMatrix();
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) m[4 * r + c] = R(r, c);
        m[4 * r + 3] = t[r];
    }
    m[12] = m[13] = m[14] = 0;
    m[15] = 1;
}

/* One corner of one tag seen in one photo: the pixel it should project to. */
struct CornerCost {
    double X, Y; /* tag frame, z = 0 */
    double u, v; /* observed pixel */
    double w;    /* 1 / corner sigma (px) */
    template <typename T>
    bool operator()(const T *tq, const T *tt, const T *cq, const T *ct, const T *k, T *r) const {
        T pt[3] = {T(X), T(Y), T(0)}, pw[3], pc[3];
        ceres::UnitQuaternionRotatePoint(tq, pt, pw);
        for (int i = 0; i < 3; i++) pw[i] += tt[i];
        ceres::UnitQuaternionRotatePoint(cq, pw, pc);
        for (int i = 0; i < 3; i++) pc[i] += ct[i];
        /* Behind the camera: a large constant residual keeps the cost finite
         * (the robust loss caps its weight) instead of dividing by ~0. */
        if (!(pc[2] > T(1e-9))) {
            r[0] = T(1e3);
            r[1] = T(1e3);
            return true;
        }
        T x = pc[0] / pc[2], y = pc[1] / pc[2];
        T r2 = x * x + y * y;
        T radial = T(1) + k[4] * r2 + k[5] * r2 * r2 + k[8] * r2 * r2 * r2;
        T xd = x * radial + T(2) * k[6] * x * y + k[7] * (r2 + T(2) * x * x);
        T yd = y * radial + k[6] * (r2 + T(2) * y * y) + T(2) * k[7] * x * y;
        r[0] = (k[0] * xd + k[2] - T(u)) * T(w);
        r[1] = (k[1] * yd + k[3] - T(v)) * T(w);
        return true;
    }
};

/* A control point: the tag point (centre or corner) in world coordinates
 * should be where the total station measured it, weighted by its sigma. */
struct ControlCost {
    double X, Y;        /* tag frame point */
    double w[3];        /* measured world point */
    double inv_sigma;
    template <typename T>
    bool operator()(const T *tq, const T *tt, T *r) const {
        T pt[3] = {T(X), T(Y), T(0)}, pw[3];
        ceres::UnitQuaternionRotatePoint(tq, pt, pw);
        for (int i = 0; i < 3; i++) r[i] = (pw[i] + tt[i] - T(w[i])) * T(inv_sigma);
        return true;
    }
};

void tag_point(double size, int corner, double *X, double *Y) {
    double h = 0.5 * size;
    static const double cx[4] = {-1, 1, 1, -1}, cy[4] = {1, 1, -1, -1};
    if (corner < 0 || corner > 3) {
        *X = *Y = 0;
    } else {
        *X = cx[corner] * h;
        *Y = cy[corner] * h;
    }
}

} // namespace

extern "C" bool mr_ba_solve(mr_ba_problem *p, char *msg, size_t msg_size) {
    /* Ceres logs through glog on stderr (rank-deficient covariances, the
     * minimiser's stops); mrcheck reports on its own, in one line. */
    FLAGS_minloglevel = google::GLOG_FATAL;
    try {
        /* Every parameter block in one buffer, in a fixed order: Ceres
         * orders the covariance's blocks by address, so separate heap
         * blocks would make its last digits depend on the heap's state. */
        std::vector<double> buf(7 * (size_t)p->ntags + 7 * (size_t)p->nphotos + 9);
        double *tq = buf.data(), *tt = tq + 4 * (size_t)p->ntags;
        double *cq = tt + 3 * (size_t)p->ntags, *ct = cq + 4 * (size_t)p->nphotos;
        double *k = ct + 3 * (size_t)p->nphotos;
        for (int i = 0; i < p->ntags; i++) split_pose(p->tag + 16 * i, &tq[4 * i], &tt[3 * i]);
        for (int j = 0; j < p->nphotos; j++) split_pose(p->cam + 16 * j, &cq[4 * j], &ct[3 * j]);
        for (int i = 0; i < 9; i++) k[i] = p->intr[i];

        ceres::Problem::Options po;
        po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
        po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
        ceres::QuaternionManifold qman;
        std::unique_ptr<ceres::SubsetManifold> kman(new ceres::SubsetManifold(9, {6, 7, 8}));
        std::vector<bool> tag_used(p->ntags, false), cam_used(p->nphotos, false);
        int nres = 0;
        const double loss_px = p->loss_px > 0 ? p->loss_px : MR_MAP_DEFAULT_LOSS_PX;
        /* The whole problem, corners weighted by w = 1 / their sigma (px)
         * and the control points by theirs, so that both speak in sigmas. */
        auto build = [&](ceres::Problem &problem, double w, ceres::LossFunction *loss) {
            nres = 0;
            for (int o = 0; o < p->nobs; o++) {
                int ti = p->obs_tag[o], pj = p->obs_photo[o];
                for (int c = 0; c < 4; c++) {
                    CornerCost *cc = new CornerCost;
                    tag_point(p->tag_size[ti], c, &cc->X, &cc->Y);
                    cc->u = p->obs_px[8 * o + 2 * c];
                    cc->v = p->obs_px[8 * o + 2 * c + 1];
                    cc->w = w;
                    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CornerCost, 2, 4, 3, 4, 3, 9>(cc), loss,
                                             &tq[4 * ti], &tt[3 * ti], &cq[4 * pj], &ct[3 * pj], k);
                    nres += 2;
                }
                tag_used[ti] = cam_used[pj] = true;
            }
            if (nres == 0) return;
            for (int i = 0; i < p->ntags; i++)
                if (tag_used[i]) problem.SetManifold(&tq[4 * i], &qman);
            for (int j = 0; j < p->nphotos; j++)
                if (cam_used[j]) problem.SetManifold(&cq[4 * j], &qman);
            if (p->refine_intrinsics)
                problem.SetManifold(k, kman.get());
            else
                problem.SetParameterBlockConstant(k);
            if (p->fixed_tag >= 0) {
                problem.SetParameterBlockConstant(&tq[4 * p->fixed_tag]);
                problem.SetParameterBlockConstant(&tt[3 * p->fixed_tag]);
            }
            for (int c = 0; c < p->ncontrol; c++) {
                if (p->ctl_use && !p->ctl_use[c]) continue;
                int ti = p->ctl_tag[c];
                if (!tag_used[ti]) continue;
                ControlCost *cc = new ControlCost;
                tag_point(p->tag_size[ti], p->ctl_corner[c], &cc->X, &cc->Y);
                for (int a = 0; a < 3; a++) cc->w[a] = p->ctl_world[3 * c + a];
                cc->inv_sigma = 1.0 / p->ctl_sigma[c];
                problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ControlCost, 3, 4, 3>(cc), nullptr,
                                         &tq[4 * ti], &tt[3 * ti]);
            }
        };
        ceres::Solver::Options so;
        so.max_num_iterations = p->max_iterations > 0 ? p->max_iterations : 100;
        so.num_threads = p->threads > 0 ? p->threads : 1;
        so.linear_solver_type = ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE)
                                    ? ceres::SPARSE_SCHUR
                                    : ceres::DENSE_SCHUR;
        so.function_tolerance = 1e-10;
        so.parameter_tolerance = 1e-10;
        so.logging_type = ceres::SILENT;
        StopOnSignal stop;
        so.callbacks.push_back(&stop);
        ceres::Solver::Summary sum;
        /* Pass 1: corners at 1 px. Their sigma is then estimated from the
         * residuals (floored: synthetic corners can be near exact) and pass
         * 2 weights them by it, which is what the control points' sigmas
         * are weighed against and what the covariance needs. */
        ceres::HuberLoss loss1(loss_px);
        std::unique_ptr<ceres::Problem> problem(new ceres::Problem(po));
        build(*problem, 1.0, &loss1);
        if (nres == 0) {
            snprintf(msg, msg_size, "no observations to adjust");
            return false;
        }
        ceres::Solve(so, problem.get(), &sum);
        if (!solved(sum, msg, msg_size)) return false;
        int iters = (int)sum.iterations.size();
        auto corner_ss = [&](int *count) {
            double ss = 0;
            int nc = 0;
            for (int o = 0; o < p->nobs; o++) {
                int ti = p->obs_tag[o], pj = p->obs_photo[o];
                for (int c = 0; c < 4; c++) {
                    CornerCost cc;
                    tag_point(p->tag_size[ti], c, &cc.X, &cc.Y);
                    cc.u = p->obs_px[8 * o + 2 * c];
                    cc.v = p->obs_px[8 * o + 2 * c + 1];
                    cc.w = 1;
                    double r[2];
                    cc(&tq[4 * ti], &tt[3 * ti], &cq[4 * pj], &ct[3 * pj], k, r);
                    ss += r[0] * r[0] + r[1] * r[1];
                    nc++;
                }
            }
            *count = nc;
            return ss;
        };
        int tangent = 0;
        for (int i = 0; i < p->ntags; i++) tangent += tag_used[i] ? 6 : 0;
        for (int j = 0; j < p->nphotos; j++) tangent += cam_used[j] ? 6 : 0;
        if (p->fixed_tag >= 0) tangent -= 6;
        tangent += p->refine_intrinsics ? 6 : 0;
        int nc = 0;
        double ss = corner_ss(&nc);
        int dof = nres - tangent;
        double sigma1 = std::sqrt(ss / (dof > 0 ? dof : nres));
        double w = 1.0 / std::max(sigma1, MR_BA_SIGMA_FLOOR_PX);
        ceres::HuberLoss loss2(loss_px * w);
        problem.reset(new ceres::Problem(po));
        build(*problem, w, &loss2);
        ceres::Solve(so, problem.get(), &sum);
        if (!solved(sum, msg, msg_size)) return false;
        p->iterations = iters + (int)sum.iterations.size();
        ss = corner_ss(&nc);
        p->rms_px = std::sqrt(ss / (2.0 * nc));
        p->sigma_px = std::sqrt(ss / (dof > 0 ? dof : nres));

        for (int i = 0; i < p->ntags; i++) join_pose(&tq[4 * i], &tt[3 * i], p->tag + 16 * i);
        for (int j = 0; j < p->nphotos; j++) join_pose(&cq[4 * j], &ct[3 * j], p->cam + 16 * j);
        for (int i = 0; i < 9; i++) p->intr[i] = k[i];

        if (p->want_cov && p->tag_cov) {
            for (int i = 0; i < 36 * p->ntags; i++) p->tag_cov[i] = NAN;
            ceres::Covariance::Options co;
            co.num_threads = so.num_threads;
            co.algorithm_type = ceres::SPARSE_QR;
            /* A rank-deficient problem (a gauge left free) fails here;
             * then the sigmas stay NaN and the map says "unknown". */
            ceres::Covariance cov(co);
            std::vector<std::pair<const double *, const double *>> blocks;
            for (int i = 0; i < p->ntags; i++) {
                if (!tag_used[i] || i == p->fixed_tag) continue;
                blocks.push_back({&tq[4 * i], &tq[4 * i]});
                blocks.push_back({&tq[4 * i], &tt[3 * i]});
                blocks.push_back({&tt[3 * i], &tt[3 * i]});
            }
            if (cov.Compute(blocks, problem.get())) {
                /* QuaternionManifold's tangent is half
                 * the rotation angle (q = [cos|d|, sin|d| d/|d|]), and it
                 * perturbs on the left, i.e. about world axes. */
                /* The residuals are in sigmas already (pass 2's weights). */
                double s2 = 1.0;
                for (int i = 0; i < p->ntags; i++) {
                    double *C = p->tag_cov + 36 * i;
                    if (i == p->fixed_tag) {
                        for (int a = 0; a < 36; a++) C[a] = 0;
                        continue;
                    }
                    if (!tag_used[i]) continue;
                    double rr[9], rt[9], tt3[9];
                    cov.GetCovarianceBlockInTangentSpace(&tq[4 * i], &tq[4 * i], rr);
                    cov.GetCovarianceBlockInTangentSpace(&tq[4 * i], &tt[3 * i], rt);
                    cov.GetCovarianceBlockInTangentSpace(&tt[3 * i], &tt[3 * i], tt3);
                    for (int a = 0; a < 3; a++)
                        for (int b = 0; b < 3; b++) {
                            C[6 * a + b] = 4 * s2 * rr[3 * a + b];
                            C[6 * a + 3 + b] = 2 * s2 * rt[3 * a + b];
                            C[6 * (3 + b) + a] = 2 * s2 * rt[3 * a + b];
                            C[6 * (3 + a) + 3 + b] = s2 * tt3[3 * a + b];
                        }
                }
            }
        }
        return true;
    } catch (const std::exception &e) {
        snprintf(msg, msg_size, "bundle adjustment: %s", e.what());
        return false;
    }
}

extern "C" bool mr_ba_rigid_fit(const double *local, const double *world, const double *w, int n, double out[16]) {
    if (n < 3) return false;
    Eigen::Vector3d cl = Eigen::Vector3d::Zero(), cw = Eigen::Vector3d::Zero();
    double sw = 0;
    for (int i = 0; i < n; i++) {
        cl += w[i] * Eigen::Vector3d(local[3 * i], local[3 * i + 1], local[3 * i + 2]);
        cw += w[i] * Eigen::Vector3d(world[3 * i], world[3 * i + 1], world[3 * i + 2]);
        sw += w[i];
    }
    if (!(sw > 0)) return false;
    cl /= sw;
    cw /= sw;
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    double spread = 0;
    for (int i = 0; i < n; i++) {
        Eigen::Vector3d a = Eigen::Vector3d(local[3 * i], local[3 * i + 1], local[3 * i + 2]) - cl;
        Eigen::Vector3d b = Eigen::Vector3d(world[3 * i], world[3 * i + 1], world[3 * i + 2]) - cw;
        H += w[i] * a * b.transpose();
        spread += w[i] * a.squaredNorm();
    }
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Vector3d s = svd.singularValues();
    /* Collinear points leave the rotation about their line free: the
     * second singular value vanishes against the spread. */
    if (!(s(1) > 1e-9 * spread)) return false;
    Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    if ((V * U.transpose()).determinant() < 0) D(2, 2) = -1;
    Eigen::Matrix3d R = V * D * U.transpose();
    Eigen::Vector3d t = cw - R * cl;
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) out[4 * r + c] = R(r, c);
        out[4 * r + 3] = t(r);
    }
    out[12] = out[13] = out[14] = 0;
    out[15] = 1;
    return true;
}

extern "C" void mr_ba_rotation_mean(const double *R, const double *w, int n, double out[9]) {
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    for (int i = 0; i < n; i++)
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) S(r, c) += w[i] * R[9 * i + 3 * r + c];
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(S, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    if ((U * V.transpose()).determinant() < 0) D(2, 2) = -1;
    Eigen::Matrix3d M = U * D * V.transpose();
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) out[3 * r + c] = M(r, c);
}
