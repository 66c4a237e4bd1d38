#pragma once
// Camera side of the playback (dive_player.h): Aravis' fake GigE Vision camera served in this
// process on the loopback interface (arv_gv_fake_camera_new("lo"), GVCP on 127.0.0.1:3956 and
// GVSP streaming through the kernel's UDP stack), which navd opens as camera_id 127.0.0.1.
// Only one can listen per network namespace. It streams the fake's own test pattern at the rate
// and trigger navd sets: the dive's image times and rendered frames are not reproduced.

#include <string>

namespace nav::hil {

class FakeGigeCamera {
 public:
  FakeGigeCamera() = default;
  ~FakeGigeCamera();
  FakeGigeCamera(const FakeGigeCamera&) = delete;
  FakeGigeCamera& operator=(const FakeGigeCamera&) = delete;

  /// Starts the fake with this serial number; "" on success, else why not.
  std::string start(const std::string& serial);
  bool running() const { return camera_ != nullptr; }
  /// The address navd opens it by.
  static constexpr const char* kAddress = "127.0.0.1";

 private:
  void* camera_ = nullptr;  ///< ArvGvFakeCamera*
};

}  // namespace nav::hil
