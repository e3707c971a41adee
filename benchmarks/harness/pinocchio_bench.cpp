// Runtime benchmark: aggsym's generated C against Pinocchio C++ (the `pin` wheel), same states, same process.
//
//   pinocchio_bench SECONDS STATES CALLS OUT.json NAME URDF [NAME URDF ...] [--constrained NAME URDF FRAMES ...]
//
// For each robot: the Pinocchio model of the URDF (pinocchio::urdf::buildModel(path, model): fixed base; with
// JointModelFreeFlyer for a model generated with --floating-base quaternion; with the composite root PX PY PZ RX RY
// RZ for --floating-base euler); the
// joint order is checked against the generated code's coordinates; STATES random states (q uniform in
// [-pi, pi], qd, qdd, tau standard normal; continuous joints get (cos, sin) in Pinocchio's q) are precomputed.
// First both sides are evaluated on the first few states and compared (relative error per pair); then each
// pair is timed in interleaved batches (one batch = CALLS calls on consecutive states, cycling through the
// STATES; a generated batch, then a Pinocchio batch on the same states, repeated for about SECONDS), and the
// median of the per-batch means is reported in ns per call, wall clock and thread CPU time.  crba and aba are
// timed in both of Pinocchio's conventions (LOCAL, its default, and WORLD) and the faster one is reported.
// Beyond the five, where the generated model has them: inverse_dynamics_derivatives against
// computeRNEADerivatives (dtau_dq, dtau_dv), forward_dynamics_derivatives against computeABADerivatives (ddq_dq,
// ddq_dv), frame_jacobians against one computeJointJacobians (+ updateFramePlacements, timed with and without)
// and getFrameJacobian(LOCAL_WORLD_ALIGNED) for each of the generated code's frames (URDF links, Pinocchio's
// BODY frames), regressor against computeJointTorqueRegressor (the full matrices compared).  Batches are short
// (tens of microseconds) so that most hold no preemption on a shared machine and the median ignores those that
// do.
//
// Peers (bench.h, bench_peer: the generated C compiled -O3, the CasADi peer at -O2 and -O3) of a robot: each is
// checked against Pinocchio on the first states for the five routines, then its timer runs in the same batches as
// the generated one (after it, before Pinocchio's), and its median, quantiles and error go to the pair's "peers".
//
// --constrained NAME URDF FRAME,FRAME,...: a model generated with --floating-base and --constraints, each listed
// frame a point contact with the world; its constrained forward dynamics is timed against
// pinocchio::constraintDynamics.  Pinocchio's model has the composite root joint PX, PY, PZ, RX, RY, RZ (aggsym's
// free root, coordinate for coordinate), one RigidConstraintModel CONTACT_3D at each frame
// (initConstraintDynamics once; default ProximalSettings: mu = 0, one exact solve), in LOCAL_WORLD_ALIGNED
// (lambda in world axes, as aggsym's) and LOCAL; the faster is reported.  The states' qd are projected onto the
// null space of the contacts' Jacobian: Pinocchio's drift is J' qd only where the contact points are at rest.
#define PINOCCHIO_DISABLE_UNSUPPORTED_WARNINGS  // constraintDynamics is marked "the API will change"
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/constrained-dynamics.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/regressor.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "bench.h"
#include "pinocchio_common.hpp"

namespace {

// the five pairs, then those beyond them (the derivatives and the regressor are emitted on request, the frame
// Jacobians by default; each is timed where the generated model has it)
const char *const PAIRS[] = {"inertia",
                             "nonlinear_effects",
                             "inverse_dynamics",
                             "forward_dynamics",
                             "inertia_inverse",
                             "inverse_dynamics_derivatives",
                             "forward_dynamics_derivatives",
                             "frame_jacobians",
                             "regressor"};
const char *const PINOCCHIO[] = {"crba",
                                 "nonLinearEffects",
                                 "rnea",
                                 "aba",
                                 "computeMinverse",
                                 "computeRNEADerivatives",
                                 "computeABADerivatives",
                                 "computeJointJacobians + getFrameJacobian",
                                 "computeJointTorqueRegressor"};
const int NPAIRS = 9;
// crba and aba take a convention (default LOCAL); both are timed and the faster one is Pinocchio's time.  The
// frame Jacobians are timed with and without updateFramePlacements (getFrameJacobian does not read oMf).
const char *const VARIANT[][2] = {{"LOCAL", "WORLD"}, {"", ""}, {"", ""}, {"LOCAL", "WORLD"}, {"", ""},
                                  {"", ""},           {"", ""}, {"with updateFramePlacements", "without"},
                                  {"", ""}};
// constraintDynamics: the contacts' reference frame (LOCAL_WORLD_ALIGNED is aggsym's lambda); the faster counts.
const pinocchio::ReferenceFrame CONTACT_FRAME[] = {pinocchio::LOCAL_WORLD_ALIGNED, pinocchio::LOCAL};
const char *const CONTACT_FRAME_NAME[] = {"LOCAL_WORLD_ALIGNED", "LOCAL"};

// The pairs of one fixed-base robot (the five, then those beyond them the generated model has); returns nonzero
// on an error (after a message).
int bench_robot(FILE *out, const std::string &name, const std::string &path, unsigned seed, double seconds,
                int nstates, int calls) {
  const bench_model *bm = nullptr;
  for (int k = 0; bench_models[k]; ++k)
    if (name == bench_models[k]->name) bm = bench_models[k];
  if (!bm) {
    std::fprintf(stderr, "no generated model %s linked in\n", name.c_str());
    return 2;
  }
  pinocchio::Model model;
  if (bm->free_flyer == 2) {  // aggsym's --floating-base euler: o1 o2 o3 theta4 theta5 theta6 = PX PY PZ RX RY RZ
    pinocchio::JointModelComposite root;
    root.addJoint(pinocchio::JointModelPX());
    root.addJoint(pinocchio::JointModelPY());
    root.addJoint(pinocchio::JointModelPZ());
    root.addJoint(pinocchio::JointModelRX());
    root.addJoint(pinocchio::JointModelRY());
    root.addJoint(pinocchio::JointModelRZ());
    pinocchio::urdf::buildModel(path, root, "root_joint", model);
  } else if (bm->free_flyer) {
    pinocchio::urdf::buildModel(path, pinocchio::JointModelFreeFlyer(), model);
  } else {
    pinocchio::urdf::buildModel(path, model);
  }
  pinocchio::Data data(model);
  const int n = bm->nv, nq = bm->nq;
  if (model.nv != n) {
    std::fprintf(stderr, "%s: Pinocchio nv = %d, generated nv = %d\n", name.c_str(), (int)model.nv, n);
    return 1;
  }
  std::vector<int> continuous;
  if (!same_joints(model, bm->joints, name, continuous)) return 1;
  States s = random_states(model, continuous, nstates, seed, bm->free_flyer == 1);
  bench_states cs = {s.count, nq, n, s.q.data(), s.qd.data(), s.qdd.data(), s.tau.data(), bm->p};
  // the frames of frame_jacobians: Pinocchio's frames of those URDF links (BODY frames)
  std::vector<pinocchio::FrameIndex> frame_ids;
  for (int f = 0; f < bm->nframes; ++f) {
    if (!model.existFrame(bm->frames[f], pinocchio::BODY)) {
      std::fprintf(stderr, "%s: Pinocchio's model has no link frame %s\n", name.c_str(), bm->frames[f]);
      return 1;
    }
    frame_ids.push_back(model.getFrameId(bm->frames[f], pinocchio::BODY));
  }
  const int nframes = (int)frame_ids.size();
  const int regressor_cols = 10 * ((int)model.njoints - 1);
  if (bm->regressor && bm->regressor_cols != regressor_cols) {
    std::fprintf(stderr, "%s: the generated regressor has %d columns, Pinocchio's %d\n", name.c_str(),
                 bm->regressor_cols, regressor_cols);
    return 1;
  }
  // Pinocchio's Jacobian of each frame, zeroed once: getFrameJacobian writes the columns of the frame's support
  // (the same ones on every call) and leaves the others as they are.
  std::vector<pinocchio::Data::Matrix6x> frame_J(nframes, pinocchio::Data::Matrix6x::Zero(6, n));
  std::vector<double> buf(std::max({(size_t)2 * n * n, (size_t)6 * nframes * n, (size_t)n * regressor_cols}));
  const size_t nn = (size_t)n * n;

  // Agreement on the first states.
  double err[NPAIRS] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  std::vector<double> frames_pin((size_t)6 * nframes * n);
  for (int k = 0; k < std::min(CHECK_STATES, nstates); ++k) {
    const double *q = &s.q[(size_t)k * nq], *qd = &s.qd[(size_t)k * n];
    const double *qdd = &s.qdd[(size_t)k * n], *tau = &s.tau[(size_t)k * n];
    bm->inertia(q, bm->p, buf.data());
    pinocchio::crba(model, data, s.Q[k], pinocchio::Convention::LOCAL);
    err[0] = std::max(err[0], relative_error(buf.data(), symmetric_from_upper(data.M).data(), n * n));
    pinocchio::crba(model, data, s.Q[k], pinocchio::Convention::WORLD);
    err[0] = std::max(err[0], relative_error(buf.data(), symmetric_from_upper(data.M).data(), n * n));
    bm->nonlinear_effects(q, qd, bm->p, buf.data());
    pinocchio::nonLinearEffects(model, data, s.Q[k], s.V[k]);
    err[1] = std::max(err[1], relative_error(buf.data(), data.nle.data(), n));
    bm->inverse_dynamics(q, qd, qdd, bm->p, buf.data());
    pinocchio::rnea(model, data, s.Q[k], s.V[k], s.Vd[k]);
    err[2] = std::max(err[2], relative_error(buf.data(), data.tau.data(), n));
    bm->forward_dynamics(q, qd, tau, bm->p, buf.data());
    pinocchio::aba(model, data, s.Q[k], s.V[k], s.T[k], pinocchio::Convention::LOCAL);
    err[3] = std::max(err[3], relative_error(buf.data(), data.ddq.data(), n));
    pinocchio::aba(model, data, s.Q[k], s.V[k], s.T[k], pinocchio::Convention::WORLD);
    err[3] = std::max(err[3], relative_error(buf.data(), data.ddq.data(), n));
    bm->inertia_inverse(q, bm->p, buf.data());
    pinocchio::computeMinverse(model, data, s.Q[k]);
    err[4] = std::max(err[4], relative_error(buf.data(), symmetric_from_upper(data.Minv).data(), n * n));
    // the derivatives: Pinocchio fills the full n x n matrices (row-major copies here); each matrix compared on
    // its own scale
    if (bm->inverse_dynamics_derivatives) {
      bm->inverse_dynamics_derivatives(q, qd, qdd, bm->p, buf.data(), buf.data() + nn);
      pinocchio::computeRNEADerivatives(model, data, s.Q[k], s.V[k], s.Vd[k]);
      err[5] = std::max({err[5], relative_error(buf.data(), row_major(data.dtau_dq).data(), n * n),
                         relative_error(buf.data() + nn, row_major(data.dtau_dv).data(), n * n)});
    }
    if (bm->forward_dynamics_derivatives) {
      bm->forward_dynamics_derivatives(q, qd, tau, bm->p, buf.data(), buf.data() + nn);
      pinocchio::computeABADerivatives(model, data, s.Q[k], s.V[k], s.T[k]);
      err[6] = std::max({err[6], relative_error(buf.data(), row_major(data.ddq_dq).data(), n * n),
                         relative_error(buf.data() + nn, row_major(data.ddq_dv).data(), n * n)});
    }
    if (bm->frame_jacobians && nframes) {
      bm->frame_jacobians(q, bm->p, buf.data());
      pinocchio::computeJointJacobians(model, data, s.Q[k]);
      pinocchio::updateFramePlacements(model, data);
      for (int f = 0; f < nframes; ++f) {
        pinocchio::Data::Matrix6x J = pinocchio::Data::Matrix6x::Zero(6, n);
        pinocchio::getFrameJacobian(model, data, frame_ids[f], pinocchio::LOCAL_WORLD_ALIGNED, J);
        const std::vector<double> Jr = row_major(J);
        std::copy(Jr.begin(), Jr.end(), frames_pin.begin() + (size_t)6 * f * n);
      }
      err[7] = std::max(err[7], relative_error(buf.data(), frames_pin.data(), 6 * nframes * n));
    }
    if (bm->regressor) {
      bm->regressor(q, qd, qdd, bm->p, buf.data());
      pinocchio::computeJointTorqueRegressor(model, data, s.Q[k], s.V[k], s.Vd[k]);
      err[8] = std::max(err[8], relative_error(buf.data(), row_major(data.jointTorqueRegressor).data(),
                                               n * regressor_cols));
    }
  }

  // The peers of this robot (the five routines only), checked against Pinocchio on the same first states.
  std::vector<Peer> peers[NPAIRS];
  for (int k = 0; bench_peers[k]; ++k) {
    const bench_model *pm = bench_peers[k]->model;
    if (name != pm->name) continue;
    double perr[5] = {0, 0, 0, 0, 0};
    for (int i = 0; i < std::min(CHECK_STATES, nstates); ++i) {
      const double *q = &s.q[(size_t)i * nq], *qd = &s.qd[(size_t)i * n];
      const double *qdd = &s.qdd[(size_t)i * n], *tau = &s.tau[(size_t)i * n];
      pm->inertia(q, pm->p, buf.data());
      pinocchio::crba(model, data, s.Q[i]);
      perr[0] = std::max(perr[0], relative_error(buf.data(), symmetric_from_upper(data.M).data(), n * n));
      pm->nonlinear_effects(q, qd, pm->p, buf.data());
      pinocchio::nonLinearEffects(model, data, s.Q[i], s.V[i]);
      perr[1] = std::max(perr[1], relative_error(buf.data(), data.nle.data(), n));
      pm->inverse_dynamics(q, qd, qdd, pm->p, buf.data());
      pinocchio::rnea(model, data, s.Q[i], s.V[i], s.Vd[i]);
      perr[2] = std::max(perr[2], relative_error(buf.data(), data.tau.data(), n));
      pm->forward_dynamics(q, qd, tau, pm->p, buf.data());
      pinocchio::aba(model, data, s.Q[i], s.V[i], s.T[i]);
      perr[3] = std::max(perr[3], relative_error(buf.data(), data.ddq.data(), n));
      pm->inertia_inverse(q, pm->p, buf.data());
      pinocchio::computeMinverse(model, data, s.Q[i]);
      perr[4] = std::max(perr[4], relative_error(buf.data(), symmetric_from_upper(data.Minv).data(), n * n));
    }
    const bench_timer pt[5] = {pm->t_inertia, pm->t_nonlinear_effects, pm->t_inverse_dynamics,
                               pm->t_forward_dynamics, pm->t_inertia_inverse};
    for (int r = 0; r < 5; ++r) peers[r].push_back({bench_peers[k]->label, pt[r], perr[r]});
  }

  auto timer = [&](auto &&call) -> Timer {
    return [&, call](int first, double *cpu) { return batch(s.count, calls, first, cpu, call); };
  };
  auto crba_call = [&](pinocchio::Convention c) {
    return [&, c](int i) {
      pinocchio::crba(model, data, s.Q[i], c);
      return data.M(0, 0);
    };
  };
  auto aba_call = [&](pinocchio::Convention c) {
    return [&, c](int i) {
      pinocchio::aba(model, data, s.Q[i], s.V[i], s.T[i], c);
      return data.ddq[0];
    };
  };
  // every emitted frame's Jacobian from one computeJointJacobians, with updateFramePlacements (oMf of every
  // frame, as the usual call sequence has it) or without (getFrameJacobian reads oMi and the frame's placement)
  auto frames_call = [&](bool update_frames) {
    return [&, update_frames](int i) {
      pinocchio::computeJointJacobians(model, data, s.Q[i]);
      if (update_frames) pinocchio::updateFramePlacements(model, data);
      double acc = 0.0;
      for (int f = 0; f < nframes; ++f) {
        pinocchio::getFrameJacobian(model, data, frame_ids[f], pinocchio::LOCAL_WORLD_ALIGNED, frame_J[f]);
        acc += frame_J[f](0, n - 1);
      }
      return acc;
    };
  };
  std::vector<std::pair<std::string, Timer>> pin_timer[NPAIRS] = {
      {{VARIANT[0][0], timer(crba_call(pinocchio::Convention::LOCAL))},
       {VARIANT[0][1], timer(crba_call(pinocchio::Convention::WORLD))}},
      {{"", timer([&](int i) {
          pinocchio::nonLinearEffects(model, data, s.Q[i], s.V[i]);
          return data.nle[0];
        })}},
      {{"", timer([&](int i) {
          pinocchio::rnea(model, data, s.Q[i], s.V[i], s.Vd[i]);
          return data.tau[0];
        })}},
      {{VARIANT[3][0], timer(aba_call(pinocchio::Convention::LOCAL))},
       {VARIANT[3][1], timer(aba_call(pinocchio::Convention::WORLD))}},
      {{"", timer([&](int i) {
          pinocchio::computeMinverse(model, data, s.Q[i]);
          return data.Minv(0, 0);
        })}},
      {{"", timer([&](int i) {
          pinocchio::computeRNEADerivatives(model, data, s.Q[i], s.V[i], s.Vd[i]);
          return data.dtau_dq(0, 0) + data.dtau_dv(0, 0);
        })}},
      {{"", timer([&](int i) {
          pinocchio::computeABADerivatives(model, data, s.Q[i], s.V[i], s.T[i]);
          return data.ddq_dq(0, 0) + data.ddq_dv(0, 0);
        })}},
      {{VARIANT[7][0], timer(frames_call(true))}, {VARIANT[7][1], timer(frames_call(false))}},
      {{"", timer([&](int i) {
          pinocchio::computeJointTorqueRegressor(model, data, s.Q[i], s.V[i], s.Vd[i]);
          return data.jointTorqueRegressor(0, 0);
        })}},
  };
  bench_timer ours_timer[NPAIRS] = {bm->t_inertia,
                                    bm->t_nonlinear_effects,
                                    bm->t_inverse_dynamics,
                                    bm->t_forward_dynamics,
                                    bm->t_inertia_inverse,
                                    bm->t_inverse_dynamics_derivatives,
                                    bm->t_forward_dynamics_derivatives,
                                    nframes ? bm->t_frame_jacobians : nullptr,
                                    bm->t_regressor};

  std::string frames_json;
  for (int f = 0; f < nframes; ++f)
    frames_json += (f ? ", \"" : "\"") + json_escape(bm->frames[f]) + "\"";
  std::fprintf(out,
               "{\"name\": \"%s\", \"urdf\": \"%s\", \"nq\": %d, \"nv\": %d, \"free_flyer\": %s, "
               "\"pinocchio_nq\": %d, \"frames\": [%s], \"regressor_cols\": %d, \"pairs\": [",
               json_escape(name).c_str(), json_escape(path).c_str(), nq, n, bm->free_flyer ? "true" : "false",
               (int)model.nq, frames_json.c_str(),
               bm->regressor ? regressor_cols : 0);
  bool first = true;
  for (int k = 0; k < NPAIRS; ++k) {
    if (!ours_timer[k]) continue;  // a routine the model was generated without
    time_pair(out, first, name, PAIRS[k], PINOCCHIO[k], pin_timer[k], ours_timer[k], cs, buf.data(), seconds, calls,
              err[k], "", peers[k]);
    first = false;
  }
  std::fprintf(out, "]}");
  return 0;
}

// Constrained forward dynamics of a floating-base robot on point contacts (the frames, comma-separated) against
// constraintDynamics; returns nonzero on an error (after a message).
int bench_constrained(FILE *out, const std::string &name, const std::string &path, const std::string &frame_list,
                      unsigned seed, double seconds, int nstates, int calls) {
  const bench_constrained_model *bm = nullptr;
  for (int k = 0; bench_constrained_models[k]; ++k)
    if (name == bench_constrained_models[k]->name) bm = bench_constrained_models[k];
  if (!bm) {
    std::fprintf(stderr, "no generated constrained model %s linked in\n", name.c_str());
    return 2;
  }
  // aggsym's --floating-base: o1 o2 o3 theta4 theta5 theta6 of the root = PX, PY, PZ, RX, RY, RZ in sequence
  pinocchio::JointModelComposite root;
  root.addJoint(pinocchio::JointModelPX());
  root.addJoint(pinocchio::JointModelPY());
  root.addJoint(pinocchio::JointModelPZ());
  root.addJoint(pinocchio::JointModelRX());
  root.addJoint(pinocchio::JointModelRY());
  root.addJoint(pinocchio::JointModelRZ());
  pinocchio::Model model;
  pinocchio::urdf::buildModel(path, root, "root_joint", model);
  const int n = bm->nq, nc = bm->nc;
  if (model.nv != n) {
    std::fprintf(stderr, "%s: Pinocchio nv = %d, generated nq = %d\n", name.c_str(), (int)model.nv, n);
    return 1;
  }
  std::vector<int> continuous;
  if (!same_joints(model, bm->joints, name, continuous)) return 1;
  std::vector<std::string> frames;
  for (size_t at = 0; at <= frame_list.size();) {
    const size_t end = std::min(frame_list.find(',', at), frame_list.size());
    frames.push_back(frame_list.substr(at, end - at));
    at = end + 1;
  }
  if (3 * (int)frames.size() != nc) {
    std::fprintf(stderr, "%s: %d contact frames, %d constraint rows in the generated code\n", name.c_str(),
                 (int)frames.size(), nc);
    return 1;
  }
  ConstraintModels contacts[2];
  ConstraintDatas contact_datas[2];
  pinocchio::Data data[2] = {pinocchio::Data(model), pinocchio::Data(model)};
  pinocchio::ProximalSettings settings[2];  // default: mu = 0, one iteration (an exact solve)
  for (const std::string &frame : frames) {
    if (!model.existFrame(frame)) {
      std::fprintf(stderr, "%s: Pinocchio's model has no frame %s\n", name.c_str(), frame.c_str());
      return 1;
    }
    const pinocchio::Frame &f = model.frames[model.getFrameId(frame)];
    for (int v = 0; v < 2; ++v)
      contacts[v].emplace_back(pinocchio::CONTACT_3D, model, f.parentJoint, f.placement, CONTACT_FRAME[v]);
  }
  for (int v = 0; v < 2; ++v) {
    for (const auto &c : contacts[v]) contact_datas[v].emplace_back(c);
    pinocchio::initConstraintDynamics(model, data[v], contacts[v], contact_datas[v]);
  }

  // Consistent states: qd projected onto the null space of the contact points' Jacobian (world axes).
  States s = random_states(model, continuous, nstates, seed, false);
  pinocchio::Data kin(model);
  Eigen::MatrixXd J(nc, n), J6(6, n);
  for (int k = 0; k < nstates; ++k) {
    pinocchio::computeJointJacobians(model, kin, s.Q[k]);
    for (size_t c = 0; c < contacts[0].size(); ++c) {
      J6.setZero();
      pinocchio::getFrameJacobian(model, kin, contacts[0][c].joint1_id, contacts[0][c].joint1_placement,
                                  pinocchio::LOCAL_WORLD_ALIGNED, J6);
      J.middleRows(3 * (int)c, 3) = J6.topRows(3);
    }
    const Eigen::VectorXd Jv = J * s.V[k];
    s.V[k] -= J.transpose() * (J * J.transpose()).ldlt().solve(Jv);
    for (int i = 0; i < n; ++i) s.qd[(size_t)k * n + i] = s.V[k][i];
  }
  bench_states cs = {s.count, n, n, s.q.data(), s.qd.data(), s.qdd.data(), s.tau.data(), bm->p};
  std::vector<double> buf((size_t)(n + nc));

  // Agreement on the first states: qdd for both reference frames, lambda in LOCAL_WORLD_ALIGNED (world axes).
  double err = 0.0, err_lambda = 0.0;
  int singular = 0;
  for (int k = 0; k < std::min(CHECK_STATES, nstates); ++k) {
    const size_t at = (size_t)k * n;
    if (bm->constrained_forward_dynamics(&s.q[at], &s.qd[at], &s.tau[at], bm->p, buf.data(), buf.data() + n))
      ++singular;
    for (int v = 0; v < 2; ++v) {
      pinocchio::constraintDynamics(model, data[v], s.Q[k], s.V[k], s.T[k], contacts[v], contact_datas[v],
                                    settings[v]);
      err = std::max(err, relative_error(buf.data(), data[v].ddq.data(), n));
    }
    err_lambda = std::max(err_lambda, relative_error(buf.data() + n, data[0].lambda_c.data(), nc));
  }
  auto timer = [&](int v) -> Timer {
    return [&, v](int first, double *cpu) {
      return batch(s.count, calls, first, cpu, [&, v](int i) {
        pinocchio::constraintDynamics(model, data[v], s.Q[i], s.V[i], s.T[i], contacts[v], contact_datas[v],
                                      settings[v]);
        return data[v].ddq[0];
      });
    };
  };
  std::vector<std::pair<std::string, Timer>> pin_timer = {{CONTACT_FRAME_NAME[0], timer(0)},
                                                          {CONTACT_FRAME_NAME[1], timer(1)}};
  std::string frames_json;
  for (const std::string &f : frames) frames_json += (frames_json.empty() ? "\"" : ", \"") + json_escape(f) + "\"";
  std::fprintf(out,
               "{\"name\": \"%s\", \"urdf\": \"%s\", \"frames\": [%s], \"nq\": %d, \"nc\": %d, \"pinocchio_nq\": %d, "
               "\"pairs\": [",
               json_escape(name).c_str(), json_escape(path).c_str(), frames_json.c_str(), n, nc, (int)model.nq);
  char extra[160];
  std::snprintf(extra, sizeof extra, ", \"lambda_relative_error\": %.3e, \"singular_check_states\": %d", err_lambda,
                singular);
  time_pair(out, true, name, "constrained_forward_dynamics", "constraintDynamics", pin_timer,
            bm->t_constrained_forward_dynamics, cs, buf.data(), seconds, calls, err, extra);
  std::fprintf(out, "]}");
  return 0;
}

}  // namespace

int main(int argc, char **argv) {
  std::vector<std::vector<std::string>> robots, constrained;  // (NAME, URDF), (NAME, URDF, FRAMES)
  bool usage = argc < 7;
  for (int i = 5; i < argc && !usage;) {
    const bool c = std::strcmp(argv[i], "--constrained") == 0;
    const int take = c ? 3 : 2;
    usage = i + c + take > argc;
    if (!usage) (c ? constrained : robots).emplace_back(argv + i + c, argv + i + c + take);
    i += c + take;
  }
  if (usage) {
    std::fprintf(stderr,
                 "usage: %s SECONDS STATES CALLS OUT.json NAME URDF [NAME URDF ...] "
                 "[--constrained NAME URDF FRAME,FRAME,... ...]\n",
                 argv[0]);
    return 2;
  }
  const double seconds = std::atof(argv[1]);
  const int nstates = std::atoi(argv[2]);
  const int calls = std::atoi(argv[3]);
  FILE *out = std::fopen(argv[4], "w");
  if (!out || nstates < 1 || calls < 1) {
    std::fprintf(stderr, "cannot write %s, or STATES/CALLS < 1\n", argv[4]);
    return 2;
  }
  std::fprintf(out, "{\"seconds_per_pair\": %g, \"states\": %d, \"calls_per_batch\": %d, \"robots\": [", seconds,
               nstates, calls);
  for (size_t r = 0; r < robots.size(); ++r) {
    if (r) std::fprintf(out, ", ");
    const int rc = bench_robot(out, robots[r][0], robots[r][1], 20240611u + 5u + 2u * (unsigned)r, seconds, nstates,
                               calls);
    if (rc) return rc;
    std::fflush(out);
  }
  std::fprintf(out, "], \"constrained\": [");
  for (size_t r = 0; r < constrained.size(); ++r) {
    if (r) std::fprintf(out, ", ");
    const int rc = bench_constrained(out, constrained[r][0], constrained[r][1], constrained[r][2],
                                     20240612u + (unsigned)r, seconds, nstates, calls);
    if (rc) return rc;
    std::fflush(out);
  }
  std::fprintf(out, "], \"sink\": %g}\n", (double)bench_sink);
  std::fclose(out);
  return 0;
}
