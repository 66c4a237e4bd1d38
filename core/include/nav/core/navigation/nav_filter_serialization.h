#pragma once
// NavFilter's checkpointed state, one serialize function per type serving both directions
// (core/serialization/archive.h). Layout = the order of the ar(...) calls below. Everything a
// restored filter needs to stay bit-identical to the original when fed the same further
// measurements: the initialisation state (held measurements), times, the warm-start tracker,
// the pending image and its links, the altitude, block -> image map, image / link / proposal
// records, counters, the sensors' last angles, and a recovery job in flight, AWAITED (stored
// with its result and hand-off time, so the resumed filter takes the same result at the same
// data time; a filter without an executor drops it). Pending registrations and innovation
// statistics are not carried.

#include <cstdint>
#include <string>

#include "nav/core/navigation/measurement_serialization.h"
#include "nav/core/navigation/nav_filter.h"
#include "nav/core/serialization/archive.h"

namespace nav::core {

template <class Archive>
void serialize(Archive& ar, BodyAttitude& a) {
  ar(a.roll_rad, "roll");
  ar(a.pitch_rad, "pitch");
  ar(a.heading_rad, "heading");
  ar(a.has_roll_pitch, "has_roll_pitch");
  ar(a.has_heading, "has_heading");
}

template <class Archive>
void serialize(Archive& ar, ImageRecord& im) {
  ar(im.t_us, "image t_us");
  ar(im.frame_id, "image frame_id");
  ar(im.state, "image state");
  ar(im.altitude_m, "image altitude");
  ar(im.robot_mean, "image robot mean");
  ar(im.robot_covariance, "image robot covariance");
  ar(im.relative_residual, "image relative residual");
  ar(im.initial_bound, "image initial bound");
}

template <class Archive>
void serialize(Archive& ar, LinkRecord& l) {
  ar(l.t_us, "link t_us");
  ar(l.frame_i, "link frame_i");
  ar(l.frame_j, "link frame_j");
  ar(l.state_i, "link state_i");
  ar(l.state_j, "link state_j");
  auto outcome = static_cast<std::uint8_t>(l.outcome);
  ar(outcome, "link outcome");
  if (!ar.check(outcome <= static_cast<std::uint8_t>(LinkOutcome::kNotRegistered),
                "link outcome " + std::to_string(outcome) + " unknown")) {
    return;
  }
  l.outcome = static_cast<LinkOutcome>(outcome);
  ar(l.mahalanobis_sq, "link mahalanobis_sq");
  ar(l.is_outlier, "link is_outlier");
  ar(l.z, "link z");
  ar(l.covariance, "link covariance");
  ar(l.innovation, "link innovation");
}

template <class Archive>
void serialize(Archive& ar, ProposalRecord& p) {
  ar(p.frame_id, "proposal frame_id");
  ar(p.candidates, "proposal candidates");
  ar(p.proposed, "proposal proposed");
  ar(p.accepted, "proposal accepted");
}

template <class Archive>
void serialize(Archive& ar, NavFilterCounters& c) {
  for (std::uint64_t* v : {&c.measurements,      &c.before_initialisation, &c.out_of_order,
                           &c.updates,           &c.update_failures,       &c.unused,
                           &c.predictions,       &c.images,                &c.duplicate_images,
                           &c.recoveries,        &c.recovery_failures,     &c.candidates,
                           &c.links_proposed,    &c.links_accepted,        &c.links_gated,
                           &c.registration_failed, &c.not_registered,      &c.outliers_rejected,
                           &c.outliers_accepted, &c.bound_update_failures,
                           &c.predictions_held}) {
    ar(*v, "counter");
  }
  ar(c.max_cg_relative_residual, "max_cg_relative_residual");
}

template <class Archive>
void serialize(Archive& ar, RobotStep& s) {
  ar(s.a, "robot step F or H");
  ar(s.b, "robot step Q or R");
  ar(s.meas_dim, "robot step measurement dimension");
  ar.check(s.meas_dim >= 0 && s.meas_dim <= kMaxMeasDim, "robot step measurement dimension");
}

template <class Archive>
void serialize(Archive& ar, WarmStartTracker& w) {
  ar(w.A, "A since recovery");
  ar(w.P, "P robot");
  ar(w.sigma_tt, "Σ_tt");
  ar(w.predicted, "predicted since recovery");
  ar(w.kept, "kept since recovery");
  ar(w.steps, "robot steps since recovery");
}

/// A recovery job's result without its solution matrix (its shape depends on the filter).
template <class Archive>
void serialize(Archive& ar, RecoveryResult& r) {
  bool ok = r.status.ok();
  ar(ok, "recovery job ok");
  std::string message = ok ? std::string() : r.status.to_string();
  if (!ok) ar(message, "recovery job message");
  if constexpr (Archive::kReading) {
    r.status = ok ? Status::Ok() : Status::Error(StatusCode::kNumericalFailure, message);
  }
  ar(r.iterations, "recovery job iterations");
  ar(r.mean_relative_residual, "recovery job residual");
  ar(r.column_relative_residual, "recovery job residual");
  ar(r.max_relative_residual, "recovery job residual");
  ar(r.column_residual_frobenius, "recovery job residual");
  ar(r.column_residual_spectral, "recovery job residual");
}

template <class Archive>
void NavFilter::serialize(Archive& ar) {
  ar(initialised_, "initialised");
  ar(time_us_, "time_us");
  ar(last_validity_us_, "last validity_us");
  ar(init_.first_time_us, "first time_us");
  ar(init_.held, "held measurements");
  ar(last_relative_residual_, "last relative residual");
  ar(init_.roll_pitch, "initial roll/pitch");
  ar(init_.heading, "initial heading");
  ar(init_.depth, "initial depth");
  serialize_size(ar, init_.roll_pitch_sensor, "initial roll/pitch sensor");
  serialize_size(ar, init_.heading_sensor, "initial heading sensor");
  ar(warm_, "warm start tracker");
  ar(pending_image_, "pending image");
  auto links = static_cast<std::uint32_t>(pending_links_.size());
  ar(links, "pending link count");
  if (!ar.check_count(links, 8, "pending link count")) return;
  if constexpr (Archive::kReading) pending_links_.assign(links, 0);
  for (std::size_t& row : pending_links_) serialize_size(ar, row, "pending link");
  ar(altitude_m_, "altitude");
  ar(image_of_block_, "block -> image map");
  ar(images_, "images");
  ar(links_, "links");
  ar(proposals_, "proposals");
  ar(counters_, "counters");
  ar(sensors_, "sensors");
  if constexpr (Archive::kReading) {
    const std::string error = ar.ok() ? index_error() : std::string();
    if (!ar.check(error.empty(), error)) return;
  }
  // The job in flight, awaited (the file comment).
  bool in_flight = jobs_.in_flight();
  ar(in_flight, "recovery job present");
  if (!in_flight || !ar.ok()) return;
  RecoveryOutput out;
  std::int64_t handoff_us = jobs_.handoff_us();
  if constexpr (!Archive::kReading) out = jobs_.peek();  // waits for the job
  ar(handoff_us, "recovery job hand-off time");
  ar(out.result, "recovery job result");
  const bool ok = out.result.status.ok();
  if (!ok) out.solution.resize(0, 0);
  ar.matrix(out.solution, ok ? recovery_.solution().rows() : 0, ok ? 13 : 0, !ok,
            "recovery job solution");
  if (!ok) out.marginals.resize(0, 0);
  ar.matrix(out.marginals, out.solution.rows(), 12, true, "recovery job exact marginals");
  if constexpr (Archive::kReading) {
    if (ar.ok() && jobs_.enabled()) jobs_.restore(out, handoff_us);
  }
}

}  // namespace nav::core
