// Farm protocol conversion (see convert.h).
#include "proto/farm_convert.h"

namespace mlt::farm {

v1::JobStatus toProto(const JobStatus& s) {
  v1::JobStatus p;
  p.set_format_version(wire::kFormatVersion);
  p.set_job_id(s.jobId);
  p.set_name(s.name);
  p.set_state(v1::JobState(int(s.state)));
  p.set_phase(s.phase);
  p.set_priority(s.priority);
  p.set_method(s.method);
  p.set_scene_hash(s.sceneHash);
  p.set_width(s.width);
  p.set_height(s.height);
  p.set_b(s.b);
  p.set_b_std_err(s.bStdErr);
  p.set_work_done(s.workDone);
  p.set_work_total(s.workTotal);
  p.set_units_done(s.unitsDone);
  p.set_units_total(s.unitsTotal);
  p.set_tasks_done(s.tasksDone);
  p.set_tasks_total(s.tasksTotal);
  p.set_leased_tasks(s.leasedTasks);
  p.set_eta_seconds(s.etaSeconds);
  p.set_elapsed_seconds(s.elapsedSeconds);
  p.set_bootstrap_seconds(s.bootstrapSeconds);
  p.set_error(s.error);
  p.set_failed_attempts(s.failedAttempts);
  return p;
}

JobStatus fromProto(const v1::JobStatus& p) {
  wire::checkVersion(p.format_version(), "JobStatus");
  JobStatus s;
  s.jobId = p.job_id();
  s.name = p.name();
  if (p.state() < v1::QUEUED || p.state() > v1::CANCELLED) throw wire::WireError("JobStatus.state", "unknown state");
  s.state = JobState(int(p.state()));
  s.phase = p.phase();
  s.priority = p.priority();
  s.method = p.method();
  s.sceneHash = p.scene_hash();
  s.width = p.width();
  s.height = p.height();
  s.b = p.b();
  s.bStdErr = p.b_std_err();
  s.workDone = p.work_done();
  s.workTotal = p.work_total();
  s.unitsDone = p.units_done();
  s.unitsTotal = p.units_total();
  s.tasksDone = p.tasks_done();
  s.tasksTotal = p.tasks_total();
  s.leasedTasks = p.leased_tasks();
  s.etaSeconds = p.eta_seconds();
  s.elapsedSeconds = p.elapsed_seconds();
  s.bootstrapSeconds = p.bootstrap_seconds();
  s.error = p.error();
  s.failedAttempts = p.failed_attempts();
  return s;
}

v1::Lease toProto(const Lease& l) {
  v1::Lease p;
  p.set_lease_id(l.leaseId);
  p.set_job_id(l.jobId);
  p.set_task_index(l.taskIndex);
  p.set_unit_begin(l.unitBegin);
  p.set_unit_end(l.unitEnd);
  p.set_scene_hash(l.sceneHash);
  p.set_scene_file(l.sceneFile);
  for (const auto& [name, value] : l.defines) (*p.mutable_defines())[name] = value;
  return p;
}

Lease fromProto(const v1::Lease& p) {
  if (p.unit_end() <= p.unit_begin())
    throw wire::WireError("Lease.unit_end", "empty unit range");
  Lease l;
  l.leaseId = p.lease_id();
  l.jobId = p.job_id();
  l.taskIndex = p.task_index();
  l.unitBegin = p.unit_begin();
  l.unitEnd = p.unit_end();
  l.sceneHash = p.scene_hash();
  l.sceneFile = p.scene_file();
  l.defines.insert(p.defines().begin(), p.defines().end());
  wire::validateDefines(l.defines, "Lease.defines");
  return l;
}

SubmitRequest fromProto(const v1::SubmitHeader& h, std::vector<BundleFile> files) {
  wire::checkVersion(h.format_version(), "SubmitHeader");
  SubmitRequest r;
  wire::SubmittedSettings s = wire::fromProto(h.settings());
  r.settings = s.settings;
  r.hasSize = s.hasSize;
  r.hasMaxDepth = s.hasMaxDepth;
  r.hasRrDepth = s.hasRrDepth;
  r.hasSpp = s.hasSpp;
  r.defines = s.defines;
  if (h.priority() < -1000 || h.priority() > 1000)
    throw wire::WireError("priority", std::to_string(h.priority()) + " is out of range [-1000, 1000]");
  r.priority = h.priority();
  r.name = h.name();
  if (h.scene_case() == v1::SubmitHeader::kBundleSceneFile) {
    r.bundleSceneFile = h.bundle_scene_file();
    r.bundle = std::move(files);
  } else if (h.scene_case() == v1::SubmitHeader::kCoordinatorPath) {
    if (!files.empty()) throw wire::WireError("chunk", "file chunks sent with a coordinator_path submission");
    r.coordinatorPath = h.coordinator_path();
    if (r.coordinatorPath.empty()) throw wire::WireError("coordinator_path", "empty");
  } else {
    throw wire::WireError("scene", "neither bundle_scene_file nor coordinator_path is set");
  }
  r.bundleHash = h.bundle_hash();
  return r;
}

}  // namespace mlt::farm
