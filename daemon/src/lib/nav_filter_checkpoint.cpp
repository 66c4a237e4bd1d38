// NavFilter checkpoints: map sections + the "NAVF" section (filter/nav_filter_checkpoint.h).
#include "nav/daemon/filter/nav_filter_checkpoint.h"

#include <algorithm>
#include <string>
#include <utility>

#include "nav/core/serialization/byte_io.h"
#include "nav/core/serialization/map_codec.h"

namespace nav::daemon {

using core::ByteReader;
using core::ByteWriter;
using core::Status;

/// Friend of NavFilter and SensorModels: reads and writes their private state.
struct NavFilterCheckpointAccess {
  static std::vector<std::uint8_t> encode(const NavFilter& f);
  static Status decode(ByteReader& r, NavFilter* f);

  static void put_time(ByteWriter& w, const MeasurementTime& t);
  static Status get_time(ByteReader& r, MeasurementTime* t);
  static void put_measurement(ByteWriter& w, const Measurement& m);
  static Status get_measurement(ByteReader& r, Measurement* m);
  static void put_attitude(ByteWriter& w, const std::optional<BodyAttitude>& a);
  static Status get_attitude(ByteReader& r, std::optional<BodyAttitude>* a);
  static void put_image(ByteWriter& w, const ImageRecord& im);
  static Status get_image(ByteReader& r, ImageRecord* im);
  static void put_link(ByteWriter& w, const LinkRecord& l);
  static Status get_link(ByteReader& r, LinkRecord* l);
  static void put_counters(ByteWriter& w, const NavFilterCounters& c);
  static Status get_counters(ByteReader& r, NavFilterCounters* c);
  static Status check_indices(const ByteReader& r, const NavFilter& f);
  static void put_recovery_job(ByteWriter& w, const NavFilter& f);
  static Status get_recovery_job(ByteReader& r, NavFilter* f);
  static Status restore(const core::SectionSet& sections, NavFilter* filter);
};

namespace {

/// Reads a bool stored as one byte (0 or 1).
Status get_bool(ByteReader& r, bool* b, const char* field) {
  std::uint8_t v = 0;
  if (Status s = r.u8(&v, field); !s.ok()) return s;
  if (v > 1) return r.error(std::string(field) + " byte " + std::to_string(v) + " is not 0/1");
  *b = v == 1;
  return Status::Ok();
}

Status get_int(ByteReader& r, long* v, const char* field) {
  std::int64_t x = 0;
  if (Status s = r.i64(&x, field); !s.ok()) return s;
  *v = static_cast<long>(x);
  return Status::Ok();
}

template <class Int>
Status get_small_int(ByteReader& r, Int* v, const char* field) {
  long x = 0;
  if (Status s = get_int(r, &x, field); !s.ok()) return s;
  if (x < -1 || x > (1L << 31)) return r.error(std::string(field) + " out of range");
  *v = static_cast<Int>(x);
  return Status::Ok();
}

#define NAV_TRY(expr)                            \
  do {                                           \
    if (Status s_ = (expr); !s_.ok()) return s_; \
  } while (false)

}  // namespace

void NavFilterCheckpointAccess::put_time(ByteWriter& w, const MeasurementTime& t) {
  w.i64(t.validity_us);
  w.i64(t.host_monotonic_us);
  w.i64(t.host_realtime_us);
  w.u32(t.sensor_index);
}

Status NavFilterCheckpointAccess::get_time(ByteReader& r, MeasurementTime* t) {
  std::int64_t a = 0, b = 0, c = 0;
  std::uint32_t sensor = 0;
  NAV_TRY(r.i64(&a, "validity_us"));
  NAV_TRY(r.i64(&b, "host_monotonic_us"));
  NAV_TRY(r.i64(&c, "host_realtime_us"));
  NAV_TRY(r.u32(&sensor, "sensor_index"));
  if (sensor > 0xFFFFu) return r.error("sensor_index " + std::to_string(sensor) + " > 65535");
  *t = MeasurementTime{a, b, c, static_cast<std::uint16_t>(sensor)};
  return Status::Ok();
}

static_assert(std::variant_size_v<Measurement> == 6, "a new measurement type: encode it below");

void NavFilterCheckpointAccess::put_measurement(ByteWriter& w, const Measurement& m) {
  w.u8(static_cast<std::uint8_t>(m.index()));
  put_time(w, time_of(m));
  if (const auto* x = std::get_if<DvlVelocity>(&m)) {
    for (double v : x->v_sensor_mps) w.f64(v);
  } else if (const auto* x = std::get_if<Attitude>(&m)) {
    w.f64(x->roll_rad);
    w.f64(x->pitch_rad);
    w.f64(x->heading_rad);
    w.u8(x->has_roll_pitch ? 1 : 0);
    w.u8(x->has_heading ? 1 : 0);
  } else if (const auto* x = std::get_if<AngularRate>(&m)) {
    for (double v : x->omega_sensor_radps) w.f64(v);
    for (bool b : x->has_axis) w.u8(b ? 1 : 0);
  } else if (const auto* x = std::get_if<Depth>(&m)) {
    w.f64(x->depth_m);
  } else if (const auto* x = std::get_if<Altitude>(&m)) {
    w.f64(x->altitude_m);
  } else if (const auto* x = std::get_if<ImageEvent>(&m)) {
    w.u64(x->frame_id);
  }
}

Status NavFilterCheckpointAccess::get_measurement(ByteReader& r, Measurement* m) {
  std::uint8_t kind = 0;
  MeasurementTime t;
  NAV_TRY(r.u8(&kind, "measurement kind"));
  NAV_TRY(get_time(r, &t));
  switch (kind) {
    case 0: {
      DvlVelocity x{t, {}};
      for (double& v : x.v_sensor_mps) NAV_TRY(r.f64(&v, "DVL velocity"));
      *m = x;
      return Status::Ok();
    }
    case 1: {
      Attitude x;
      x.time = t;
      NAV_TRY(r.f64(&x.roll_rad, "roll"));
      NAV_TRY(r.f64(&x.pitch_rad, "pitch"));
      NAV_TRY(r.f64(&x.heading_rad, "heading"));
      NAV_TRY(get_bool(r, &x.has_roll_pitch, "has_roll_pitch"));
      NAV_TRY(get_bool(r, &x.has_heading, "has_heading"));
      *m = x;
      return Status::Ok();
    }
    case 2: {
      AngularRate x;
      x.time = t;
      for (double& v : x.omega_sensor_radps) NAV_TRY(r.f64(&v, "angular rate"));
      for (std::size_t i = 0; i < 3; ++i) {
        bool b = false;
        NAV_TRY(get_bool(r, &b, "has_axis"));
        x.has_axis[i] = b;
      }
      *m = x;
      return Status::Ok();
    }
    case 3: {
      Depth x{t, 0.0};
      NAV_TRY(r.f64(&x.depth_m, "depth"));
      *m = x;
      return Status::Ok();
    }
    case 4: {
      Altitude x{t, 0.0};
      NAV_TRY(r.f64(&x.altitude_m, "altitude"));
      *m = x;
      return Status::Ok();
    }
    case 5: {
      ImageEvent x{t, 0};
      NAV_TRY(r.u64(&x.frame_id, "frame_id"));
      *m = x;
      return Status::Ok();
    }
    default:
      return r.error("measurement kind " + std::to_string(kind) + " unknown");
  }
}

void NavFilterCheckpointAccess::put_attitude(ByteWriter& w, const std::optional<BodyAttitude>& a) {
  w.u8(a ? 1 : 0);
  if (!a) return;
  w.f64(a->roll_rad);
  w.f64(a->pitch_rad);
  w.f64(a->heading_rad);
  w.u8(a->has_roll_pitch ? 1 : 0);
  w.u8(a->has_heading ? 1 : 0);
}

Status NavFilterCheckpointAccess::get_attitude(ByteReader& r, std::optional<BodyAttitude>* a) {
  bool present = false;
  NAV_TRY(get_bool(r, &present, "attitude present"));
  if (!present) {
    a->reset();
    return Status::Ok();
  }
  BodyAttitude x;
  NAV_TRY(r.f64(&x.roll_rad, "roll"));
  NAV_TRY(r.f64(&x.pitch_rad, "pitch"));
  NAV_TRY(r.f64(&x.heading_rad, "heading"));
  NAV_TRY(get_bool(r, &x.has_roll_pitch, "has_roll_pitch"));
  NAV_TRY(get_bool(r, &x.has_heading, "has_heading"));
  *a = x;
  return Status::Ok();
}

void NavFilterCheckpointAccess::put_image(ByteWriter& w, const ImageRecord& im) {
  w.i64(im.t_us);
  w.u64(im.frame_id);
  w.i64(im.state);
  w.f64(im.altitude_m);
  w.values(im.robot_mean);
  w.values(im.robot_covariance);
  w.f64(im.relative_residual);
  w.values(im.initial_bound);
}

Status NavFilterCheckpointAccess::get_image(ByteReader& r, ImageRecord* im) {
  NAV_TRY(r.i64(&im->t_us, "image t_us"));
  NAV_TRY(r.u64(&im->frame_id, "image frame_id"));
  NAV_TRY(get_small_int(r, &im->state, "image state"));
  NAV_TRY(r.f64(&im->altitude_m, "image altitude"));
  NAV_TRY(r.values(&im->robot_mean, "image robot mean"));
  NAV_TRY(r.values(&im->robot_covariance, "image robot covariance"));
  NAV_TRY(r.f64(&im->relative_residual, "image relative residual"));
  return r.values(&im->initial_bound, "image initial bound");
}

void NavFilterCheckpointAccess::put_link(ByteWriter& w, const LinkRecord& l) {
  w.i64(l.t_us);
  w.u64(l.frame_i);
  w.u64(l.frame_j);
  w.i64(l.state_i);
  w.i64(l.state_j);
  w.u8(static_cast<std::uint8_t>(l.outcome));
  w.f64(l.mahalanobis_sq);
  w.u8(l.is_outlier ? 1 : 0);
  w.values(l.z);
  w.values(l.covariance);
  w.values(l.innovation);
}

Status NavFilterCheckpointAccess::get_link(ByteReader& r, LinkRecord* l) {
  NAV_TRY(r.i64(&l->t_us, "link t_us"));
  NAV_TRY(r.u64(&l->frame_i, "link frame_i"));
  NAV_TRY(r.u64(&l->frame_j, "link frame_j"));
  NAV_TRY(get_small_int(r, &l->state_i, "link state_i"));
  NAV_TRY(get_small_int(r, &l->state_j, "link state_j"));
  std::uint8_t outcome = 0;
  NAV_TRY(r.u8(&outcome, "link outcome"));
  if (outcome > static_cast<std::uint8_t>(LinkOutcome::kNotRegistered)) {
    return r.error("link outcome " + std::to_string(outcome) + " unknown");
  }
  l->outcome = static_cast<LinkOutcome>(outcome);
  NAV_TRY(r.f64(&l->mahalanobis_sq, "link mahalanobis_sq"));
  NAV_TRY(get_bool(r, &l->is_outlier, "link is_outlier"));
  NAV_TRY(r.values(&l->z, "link z"));
  NAV_TRY(r.values(&l->covariance, "link covariance"));
  return r.values(&l->innovation, "link innovation");
}

void NavFilterCheckpointAccess::put_counters(ByteWriter& w, const NavFilterCounters& c) {
  for (std::uint64_t v : {c.measurements,      c.before_initialisation,
                          c.out_of_order,      c.updates,
                          c.update_failures,   c.unused,
                          c.predictions,       c.images,
                          c.duplicate_images,  c.recoveries,
                          c.recovery_failures, c.candidates,
                          c.links_proposed,    c.links_accepted,
                          c.links_gated,       c.registration_failed,
                          c.not_registered,    c.outliers_rejected,
                          c.outliers_accepted, c.bound_update_failures}) {
    w.u64(v);
  }
  w.f64(c.max_cg_relative_residual);
}

Status NavFilterCheckpointAccess::get_counters(ByteReader& r, NavFilterCounters* c) {
  for (std::uint64_t* v : {&c->measurements,      &c->before_initialisation,
                           &c->out_of_order,      &c->updates,
                           &c->update_failures,   &c->unused,
                           &c->predictions,       &c->images,
                           &c->duplicate_images,  &c->recoveries,
                           &c->recovery_failures, &c->candidates,
                           &c->links_proposed,    &c->links_accepted,
                           &c->links_gated,       &c->registration_failed,
                           &c->not_registered,    &c->outliers_rejected,
                           &c->outliers_accepted, &c->bound_update_failures}) {
    NAV_TRY(r.u64(v, "counter"));
  }
  return r.f64(&c->max_cg_relative_residual, "max_cg_relative_residual");
}

std::vector<std::uint8_t> NavFilterCheckpointAccess::encode(const NavFilter& f) {
  ByteWriter w;
  w.u8(f.initialised_ ? 1 : 0);
  w.i64(f.time_us_);
  w.i64(f.last_validity_us_);
  w.i64(f.first_time_us_);
  w.u32(static_cast<std::uint32_t>(f.pre_init_.size()));
  for (const Measurement& m : f.pre_init_) put_measurement(w, m);
  w.f64(f.last_relative_residual_);
  put_attitude(w, f.init_roll_pitch_);
  put_attitude(w, f.init_heading_);
  w.u8(f.init_depth_ ? 1 : 0);
  if (f.init_depth_) {
    put_time(w, f.init_depth_->time);
    w.f64(f.init_depth_->depth_m);
  }
  w.u64(f.init_rp_sensor_);
  w.u64(f.init_heading_sensor_);
  w.values(f.A_since_recovery_);
  w.values(f.P_robot_);
  w.values(f.sigma_tt_);
  w.u8(f.predicted_since_recovery_ ? 1 : 0);
  w.i64(f.kept_since_recovery_);
  w.i64(f.pending_image_);
  w.u32(static_cast<std::uint32_t>(f.pending_links_.size()));
  for (std::size_t l : f.pending_links_) w.u64(l);
  w.f64(f.altitude_m_);
  w.u32(static_cast<std::uint32_t>(f.image_of_block_.size()));
  for (long i : f.image_of_block_) w.i64(i);
  w.u32(static_cast<std::uint32_t>(f.images_.size()));
  for (const ImageRecord& im : f.images_) put_image(w, im);
  w.u32(static_cast<std::uint32_t>(f.links_.size()));
  for (const LinkRecord& l : f.links_) put_link(w, l);
  w.u32(static_cast<std::uint32_t>(f.proposals_.size()));
  for (const ProposalRecord& p : f.proposals_) {
    w.u64(p.frame_id);
    w.i64(p.candidates);
    w.i64(p.proposed);
    w.i64(p.accepted);
  }
  put_counters(w, f.counters_);
  w.u32(static_cast<std::uint32_t>(f.sensors_.sensors_.size()));
  for (const auto& s : f.sensors_.sensors_) w.values(s.last_rpy_sensor);
  put_recovery_job(w, f);
  return w.take();
}

Status NavFilterCheckpointAccess::decode(ByteReader& r, NavFilter* f) {
  NAV_TRY(get_bool(r, &f->initialised_, "initialised"));
  NAV_TRY(r.i64(&f->time_us_, "time_us"));
  NAV_TRY(r.i64(&f->last_validity_us_, "last validity_us"));
  NAV_TRY(r.i64(&f->first_time_us_, "first time_us"));
  std::uint32_t held = 0;
  NAV_TRY(r.u32(&held, "held measurement count"));
  NAV_TRY(r.check_count(held, 29, "held measurement count"));
  f->pre_init_.assign(held, Measurement{});
  for (Measurement& m : f->pre_init_) NAV_TRY(get_measurement(r, &m));
  NAV_TRY(r.f64(&f->last_relative_residual_, "last relative residual"));
  NAV_TRY(get_attitude(r, &f->init_roll_pitch_));
  NAV_TRY(get_attitude(r, &f->init_heading_));
  bool has_depth = false;
  NAV_TRY(get_bool(r, &has_depth, "init depth present"));
  f->init_depth_.reset();
  if (has_depth) {
    Depth d;
    NAV_TRY(get_time(r, &d.time));
    NAV_TRY(r.f64(&d.depth_m, "init depth"));
    f->init_depth_ = d;
  }
  std::uint64_t rp = 0, hd = 0;
  NAV_TRY(r.u64(&rp, "init roll/pitch sensor"));
  NAV_TRY(r.u64(&hd, "init heading sensor"));
  f->init_rp_sensor_ = rp;
  f->init_heading_sensor_ = hd;
  NAV_TRY(r.values(&f->A_since_recovery_, "A since recovery"));
  NAV_TRY(r.values(&f->P_robot_, "P robot"));
  NAV_TRY(r.values(&f->sigma_tt_, "Σ_tt"));
  NAV_TRY(get_bool(r, &f->predicted_since_recovery_, "predicted since recovery"));
  NAV_TRY(get_small_int(r, &f->kept_since_recovery_, "kept since recovery"));
  NAV_TRY(get_small_int(r, &f->pending_image_, "pending image"));
  std::uint32_t n = 0;
  NAV_TRY(r.u32(&n, "pending link count"));
  NAV_TRY(r.check_count(n, 8, "pending link count"));
  f->pending_links_.assign(n, 0);
  for (std::size_t& l : f->pending_links_) {
    std::uint64_t x = 0;
    NAV_TRY(r.u64(&x, "pending link"));
    l = static_cast<std::size_t>(x);
  }
  NAV_TRY(r.f64(&f->altitude_m_, "altitude"));
  NAV_TRY(r.u32(&n, "block count"));
  NAV_TRY(r.check_count(n, 8, "block count"));
  f->image_of_block_.assign(n, -1);
  for (long& i : f->image_of_block_) NAV_TRY(get_small_int(r, &i, "image of block"));
  NAV_TRY(r.u32(&n, "image count"));
  NAV_TRY(r.check_count(n, 8 * (5 + 12 + 144 + 36), "image count"));
  f->images_.assign(n, ImageRecord{});
  for (ImageRecord& im : f->images_) NAV_TRY(get_image(r, &im));
  NAV_TRY(r.u32(&n, "link count"));
  NAV_TRY(r.check_count(n, 8 * (6 + 35) + 2, "link count"));
  f->links_.assign(n, LinkRecord{});
  for (LinkRecord& l : f->links_) NAV_TRY(get_link(r, &l));
  NAV_TRY(r.u32(&n, "proposal count"));
  NAV_TRY(r.check_count(n, 32, "proposal count"));
  f->proposals_.assign(n, ProposalRecord{});
  for (ProposalRecord& p : f->proposals_) {
    NAV_TRY(r.u64(&p.frame_id, "proposal frame_id"));
    NAV_TRY(get_small_int(r, &p.candidates, "proposal candidates"));
    NAV_TRY(get_small_int(r, &p.proposed, "proposal proposed"));
    NAV_TRY(get_small_int(r, &p.accepted, "proposal accepted"));
  }
  NAV_TRY(get_counters(r, &f->counters_));
  NAV_TRY(r.u32(&n, "sensor count"));
  if (n != f->sensors_.sensors_.size()) {
    return r.error("checkpoint has " + std::to_string(n) + " sensors, the config " +
                   std::to_string(f->sensors_.sensors_.size()));
  }
  for (auto& s : f->sensors_.sensors_) NAV_TRY(r.values(&s.last_rpy_sensor, "sensor last angles"));
  NAV_TRY(get_recovery_job(r, f));
  NAV_TRY(r.expect_end());
  return check_indices(r, *f);
}

// The recovery thread's job in flight, awaited (nav_filter_checkpoint.h): u8 present; then
// i64 hand-off time, u8 ok, the message (u32 length + bytes) when not ok, the result's
// iterations (i64) and residuals (5 x f64), and [μ | Σ_{*r}] (ByteWriter::matrix).
void NavFilterCheckpointAccess::put_recovery_job(ByteWriter& w, const NavFilter& f) {
  const bool in_flight = f.recovery_in_flight();
  w.u8(in_flight ? 1 : 0);
  if (!in_flight) return;
  const RecoveryOutput& out = f.worker_.worker->peek();  // waits for the job
  w.i64(f.handoff_us_);
  w.u8(out.result.status.ok() ? 1 : 0);
  if (!out.result.status.ok()) {
    const std::string message = out.result.status.to_string();
    w.u32(static_cast<std::uint32_t>(message.size()));
    w.bytes(std::span(reinterpret_cast<const std::uint8_t*>(message.data()), message.size()));
  }
  w.i64(out.result.iterations);
  for (double v : {out.result.mean_relative_residual, out.result.column_relative_residual,
                   out.result.max_relative_residual, out.result.column_residual_frobenius,
                   out.result.column_residual_spectral}) {
    w.f64(v);
  }
  if (out.result.status.ok()) {
    w.matrix(out.solution);
  } else {
    w.matrix(Eigen::MatrixXd());
  }
}

Status NavFilterCheckpointAccess::get_recovery_job(ByteReader& r, NavFilter* f) {
  bool in_flight = false;
  NAV_TRY(get_bool(r, &in_flight, "recovery job present"));
  if (!in_flight) return Status::Ok();
  RecoveryOutput out;
  std::int64_t handoff_us = 0;
  NAV_TRY(r.i64(&handoff_us, "recovery job hand-off time"));
  bool ok = false;
  NAV_TRY(get_bool(r, &ok, "recovery job ok"));
  if (!ok) {
    std::uint32_t n = 0;
    NAV_TRY(r.u32(&n, "recovery job message length"));
    std::span<const std::uint8_t> text;
    NAV_TRY(r.raw(&text, n, "recovery job message"));
    out.result.status = Status::Error(core::StatusCode::kNumericalFailure,
                                      std::string(text.begin(), text.end()));
  }
  std::int64_t iterations = 0;
  NAV_TRY(r.i64(&iterations, "recovery job iterations"));
  out.result.iterations = static_cast<int>(iterations);
  for (double* v : {&out.result.mean_relative_residual, &out.result.column_relative_residual,
                    &out.result.max_relative_residual, &out.result.column_residual_frobenius,
                    &out.result.column_residual_spectral}) {
    NAV_TRY(r.f64(v, "recovery job residual"));
  }
  const Eigen::Index rows = f->recovery_.solution().rows();
  NAV_TRY(r.matrix(&out.solution, ok ? rows : 0, ok ? 13 : 0, !ok, "recovery job solution"));
  // A filter now configured without the thread drops the job (its warm start stays valid).
  if (f->worker_.worker) {
    f->worker_.worker->set_ready(out);
    f->handoff_us_ = handoff_us;
  }
  return Status::Ok();
}

Status NavFilterCheckpointAccess::check_indices(const ByteReader& r, const NavFilter& f) {
  const long images = static_cast<long>(f.images_.size());
  const int blocks = f.filter_.num_blocks();
  // One entry per block (the robot's, -1, exists before initialisation too).
  if (f.image_of_block_.size() > static_cast<std::size_t>(std::max(blocks, 1))) {
    return r.error("block -> image map has " + std::to_string(f.image_of_block_.size()) +
                   " entries for " + std::to_string(blocks) + " blocks");
  }
  for (long i : f.image_of_block_) {
    if (i < -1 || i >= images)
      return r.error("block -> image map names image " + std::to_string(i));
  }
  if (f.pending_image_ >= images) {
    return r.error("pending image " + std::to_string(f.pending_image_) + " of " +
                   std::to_string(images));
  }
  for (std::size_t l : f.pending_links_) {
    if (l >= f.links_.size()) return r.error("pending link " + std::to_string(l) + " unknown");
  }
  for (const ImageRecord& im : f.images_) {
    if (im.state >= blocks) return r.error("image state " + std::to_string(im.state) + " unknown");
  }
  for (const LinkRecord& l : f.links_) {
    if (l.state_i >= blocks || l.state_j >= blocks) return r.error("link state unknown");
  }
  if (f.kept_since_recovery_ >= blocks) return r.error("kept block unknown");
  if (f.init_rp_sensor_ >= f.sensors_.sensors_.size() ||
      f.init_heading_sensor_ >= f.sensors_.sensors_.size()) {
    return r.error("initialisation sensor index unknown");
  }
  return Status::Ok();
}

core::Status add_nav_filter_sections(const NavFilter& filter, core::SectionWriter* writer) {
  NAV_TRY(core::add_map_sections(filter.esdf(), &filter.bounds(), writer));
  NAV_TRY(core::add_recovery_section(filter.recovery(), writer));
  return writer->add(kNavFilterSectionTag, kNavFilterSectionVersion,
                     NavFilterCheckpointAccess::encode(filter));
}

core::Status restore_nav_filter(const core::SectionSet& sections, NavFilter* filter) {
  return NavFilterCheckpointAccess::restore(sections, filter);
}

Status NavFilterCheckpointAccess::restore(const core::SectionSet& sections, NavFilter* filter) {
  NavFilter next(*filter);  // everything restored into a copy: all or nothing
  std::optional<core::Esdf> esdf;
  std::optional<core::CovarianceBounds> bounds;
  NAV_TRY(core::restore_map(sections, &esdf, &bounds));
  if (bounds->options().certify_truncation != next.bounds_.options().certify_truncation) {
    return Status::Error(core::StatusCode::kInvalidArgument,
                         "NavFilter checkpoint: bounds certification differs from the options");
  }
  NAV_TRY(core::restore_recovery(sections, esdf->num_blocks(), &next.recovery_));
  next.filter_ = std::move(*esdf);
  next.bounds_ = std::move(*bounds);
  const core::SectionView* v = nullptr;
  NAV_TRY(sections.require(kNavFilterSectionTag, kNavFilterSectionVersion, &v));
  ByteReader r(v->bytes, "NAVF section", v->offset);
  NAV_TRY(NavFilterCheckpointAccess::decode(r, &next));
  *filter = std::move(next);
  return Status::Ok();
}

}  // namespace nav::daemon
