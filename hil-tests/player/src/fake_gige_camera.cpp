// FakeGigeCamera: Aravis' GigE Vision fake on lo; see fake_gige_camera.h.
#include "fake_gige_camera.h"

#include <arv.h>

namespace nav::hil {

FakeGigeCamera::~FakeGigeCamera() {
  if (camera_ != nullptr) g_object_unref(static_cast<ArvGvFakeCamera*>(camera_));
}

std::string FakeGigeCamera::start(const std::string& serial) {
  ArvGvFakeCamera* camera = arv_gv_fake_camera_new("lo", serial.c_str());
  if (camera == nullptr) return "arv_gv_fake_camera_new(\"lo\") failed";
  if (!arv_gv_fake_camera_is_running(camera)) {
    g_object_unref(camera);
    return "Aravis' fake GigE camera cannot listen on lo (GVCP port 3956 taken or no lo)";
  }
  camera_ = camera;
  return {};
}

}  // namespace nav::hil
