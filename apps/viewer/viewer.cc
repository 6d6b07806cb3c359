#include "viewer/viewer.h"

// GL types and prototypes come from gl_api.h (through surface_renderer.h); GLFW adds none.
#include "gipsi/viz/render/surface_renderer.h"
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <thread>

#include <fmt/format.h>

#include "gipsi/io/builtins.h"
#include "gipsi/viz/mouse_tool.h"
#include "gipsi/viz/render/image.h"
#include "viewer/simulation_thread.h"

namespace gipsi::viz {
namespace {

std::string g_glfw_error;

void OnGlfwError(int code, const char* message) {
  g_glfw_error = fmt::format("{} (GLFW error {:#x})", message, code);
}

/// Reads the back buffer (`width` by `height`) into a top-down image.
Image ReadBackBuffer(const GlApi& gl, int width, int height) {
  Image image{width, height, {}};
  std::vector<std::uint8_t> rows(3 * std::size_t(width) * std::size_t(height));
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.ReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
  image.rgb.resize(rows.size());
  const std::size_t stride = 3 * std::size_t(width);
  for (int y = 0; y < height; ++y)
    std::copy_n(rows.data() + std::size_t(height - 1 - y) * stride, stride,
                image.rgb.data() + std::size_t(y) * stride);
  return image;
}

/// The ray under a window pixel (x right, y down, framebuffer pixels) of the scene area that
/// starts at `left` and is `width` by `height`.
std::pair<Vec3, Vec3> MouseRay(const Camera& camera, double x, double y, int left, int width,
                               int height) {
  return camera.Ray(2 * (x - left) / width - 1, 1 - 2 * y / height, double(width) / height);
}

/// The haptic tool at `position` as a point surface: black without force, red with.
SurfaceBuffers HapticToolPoint(const Vec3& position, const Vec3& force) {
  SurfaceBuffers s;
  s.object = "haptic tool";
  s.primitive = Primitive::kPoints;
  s.size = 12;
  s.positions = {float(position.x()), float(position.y()), float(position.z())};
  s.normals = {0, 0, 0};
  const bool pushing = force.squaredNorm() > 0;
  s.colors = {pushing ? 1.0f : 0.0f, 0, 0};
  s.indices = {0};
  return s;
}

struct SurfaceUi {
  bool visible = true;
  bool wireframe = false;
  int field = 0;      // 0 = solid, else index + 1 into the object's fields
  int component = 0;  // ComponentChoices: 0 the magnitude, k component k-1
  int map = 0;        // ColorMap::Names()
};

}  // namespace

int RunViewer(const ViewerOptions& options) {
  auto load = [&options](TypeRegistry& registry) {
    RegisterBuiltins(registry);
    for (const auto& plugin : options.plugins) registry.LoadPlugin(plugin);
    Scene scene = LoadScene(options.scene, registry);
    ApplyGeometryOptions(*scene.kernel, options.as, "--as", scene.display);
    return scene;
  };
  LatestValue<FrameBuffers> frames;
  // Bad input (scene, colours, --show / --hide) throws here, before any window opens.
  SimulationThread sim(load, options.colors, frames, options.show, options.hide);
  const std::vector<bool> initially_hidden = sim.initially_hidden();
  sim.SetSpeed(options.speed);
  sim.SetAtEnd(options.at_end);

  glfwSetErrorCallback(OnGlfwError);
  if (!glfwInit()) {
    std::cerr << "gipsi: error: cannot open a window: " << g_glfw_error
              << " (no display? run under xvfb-run, or use gipsi snapshot)\n";
    return kNoDisplayExitCode;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  // Not forward-compatible: such contexts reject line widths above 1 pixel (line sets).
  const std::string title = "GiPSi - " + options.scene;
  GLFWwindow* window =
      glfwCreateWindow(options.width, options.height, title.c_str(), nullptr, nullptr);
  if (!window) {
    std::cerr << "gipsi: error: cannot open an OpenGL 3.3 window: " << g_glfw_error
              << " (no display? run under xvfb-run, or use gipsi snapshot)\n";
    glfwTerminate();
    return kNoDisplayExitCode;
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  GlApi gl;
  const std::string missing =
      gl.Load([](const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); });
  if (!missing.empty()) {
    std::cerr << "gipsi: error: the OpenGL driver lacks " << missing << "\n";
    glfwDestroyWindow(window);
    glfwTerminate();
    return kNoDisplayExitCode;
  }
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;
  ImGui::StyleColorsLight();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");

  int exit_code = 0;
  {
    SurfaceRenderer renderer(gl);
    Camera camera = options.camera;
    bool fitted = false;
    RenderOptions render;
    render.color_bar = !options.show_ui;  // the panel has the legend, with its numbers
    const std::vector<std::string> maps = ColorMap::Names();
    std::vector<SurfaceUi> ui;
    float speed = static_cast<float>(options.speed > 0 ? options.speed : 1.0);
    bool as_fast_as_possible = options.speed <= 0;
    int at_end = static_cast<int>(options.at_end);
    bool dragging_tool = false, dragging_haptic = false;
    Vec3 tool_plane_point = Vec3::Zero(), tool_plane_normal = Vec3::UnitZ();
    int frames_at_screenshot_time = 0;
    bool scripted_drag_done = !options.drag.has_value();
    if (!options.screenshot.empty() && options.screenshot_time > 0 && scripted_drag_done)
      sim.RunUntil(options.screenshot_time);
    else if (options.play)
      sim.SetPlaying(true);

    while (!glfwWindowShouldClose(window)) {
      const auto frame_start = std::chrono::steady_clock::now();
      glfwPollEvents();
      frames.Fetch();
      const FrameBuffers& frame = frames.front();
      const SimulationStatus status = sim.status();
      int fb_width = 0, fb_height = 0, win_width = 0, win_height = 0;
      glfwGetFramebufferSize(window, &fb_width, &fb_height);
      glfwGetWindowSize(window, &win_width, &win_height);
      if (fb_width <= 0 || fb_height <= 0) continue;  // minimised
      const double scale = win_width > 0 ? double(fb_width) / win_width : 1.0;
      const int panel = options.show_ui ? std::min(340, fb_width / 3) : 0;
      const int scene_width = fb_width - panel;
      if (ui.size() != status.draws.size()) {  // (re)loaded: start from the scene's choices
        ui.assign(status.draws.size(), SurfaceUi{});
        for (std::size_t i = 0; i < ui.size() && i < status.objects.size(); ++i) {
          const ColorSpec& spec = status.draws[i].color;
          ui[i].visible =
              i < initially_hidden.size() ? !initially_hidden[i] : status.draws[i].visible;
          ui[i].wireframe = status.draws[i].wireframe;
          const auto& fields = status.objects[i].fields;
          const auto f = std::find(fields.begin(), fields.end(), spec.field);
          ui[i].field = f == fields.end() ? 0 : static_cast<int>(f - fields.begin()) + 1;
          ui[i].component = spec.component + 1;
          const auto m = std::find(maps.begin(), maps.end(), spec.color_map);
          ui[i].map = m == maps.end() ? 0 : static_cast<int>(m - maps.begin());
        }
      }
      render.hidden.resize(ui.size());
      render.edges.resize(ui.size());
      for (std::size_t i = 0; i < ui.size(); ++i) {
        render.hidden[i] = !ui[i].visible;
        render.edges[i] = ui[i].wireframe;
      }
      // The mouse pulls only visible objects that can be pulled (SimulationThread::Grab).
      std::vector<bool> not_pullable(ui.size(), true);
      bool any_pullable = false;
      for (std::size_t i = 0; i < ui.size() && i < status.objects.size(); ++i) {
        not_pullable[i] = render.hidden[i] || !status.objects[i].pullable;
        any_pullable = any_pullable || status.objects[i].pullable;
      }
      if (!fitted && frame.frame >= 0) {
        camera.FitTo(frame, double(scene_width) / fb_height);
        fitted = true;
      }

      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();

      // Camera and tool from the mouse, unless the panel has it.
      if (!io.WantCaptureMouse) {
        const double mx = io.MousePos.x * scale, my = io.MousePos.y * scale;
        const bool tool_key = io.KeyCtrl || io.KeyShift;
        const Vec3 forward = (camera.target - camera.Eye()).normalized();
        if (ImGui::IsMouseClicked(ImGuiMouseButton_Left) && tool_key && status.haptic_mouse) {
          // The scene's haptic tool: dragged in the plane through it that faces the viewer.
          const auto [origin, dir] = MouseRay(camera, mx, my, panel, scene_width, fb_height);
          sim.HapticBeginDrag(forward);
          sim.HapticDragTo(origin, dir);
          dragging_haptic = true;
        } else if (ImGui::IsMouseClicked(ImGuiMouseButton_Left) && tool_key && any_pullable) {
          const auto [origin, dir] = MouseRay(camera, mx, my, panel, scene_width, fb_height);
          if (auto hit = PickSurface(frame, origin, dir, not_pullable)) {
            sim.Grab(hit->surface, hit->point);
            dragging_tool = true;
            tool_plane_point = hit->point;
            tool_plane_normal = (camera.target - camera.Eye()).normalized();
          }
        }
        if (dragging_haptic && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
          const auto [origin, dir] = MouseRay(camera, mx, my, panel, scene_width, fb_height);
          sim.HapticDragTo(origin, dir);
        } else if (dragging_tool && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
          const auto [origin, dir] = MouseRay(camera, mx, my, panel, scene_width, fb_height);
          const double denom = dir.dot(tool_plane_normal);
          if (std::abs(denom) > 1e-9)
            sim.Drag(origin + dir * ((tool_plane_point - origin).dot(tool_plane_normal) / denom));
        } else if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
          camera.Orbit(-0.4 * io.MouseDelta.x, 0.4 * io.MouseDelta.y);
        }
        if (ImGui::IsMouseDown(ImGuiMouseButton_Right) ||
            ImGui::IsMouseDown(ImGuiMouseButton_Middle)) {
          const Eigen::Matrix4f view = camera.View();
          const Vec3 right = view.block<1, 3>(0, 0).transpose().cast<double>();
          const Vec3 up = view.block<1, 3>(1, 0).transpose().cast<double>();
          const double k = camera.distance * 0.0015;
          camera.target -= k * (io.MouseDelta.x * right - io.MouseDelta.y * up);
        }
        if (io.MouseWheel != 0 && tool_key && status.haptic_mouse)
          sim.HapticPush(forward, io.MouseWheel);  // wheel up: the tool goes into the scene
        else if (io.MouseWheel != 0)
          camera.distance *= std::pow(0.9, io.MouseWheel);
      }
      if (!scripted_drag_done && fitted) {  // --drag: the same path as a real Ctrl + drag
        const auto& d = *options.drag;
        const auto [origin, dir] = MouseRay(camera, d[0], d[1], panel, scene_width, fb_height);
        if (status.haptic_mouse) {  // the haptic tool: to the end point, in its facing plane
          const auto [o, r] = MouseRay(camera, d[2], d[3], panel, scene_width, fb_height);
          sim.HapticBeginDrag((camera.target - camera.Eye()).normalized());
          sim.HapticDragTo(o, r);
          sim.HapticEndDrag();
        } else if (auto hit = PickSurface(frame, origin, dir, not_pullable)) {
          sim.Grab(hit->surface, hit->point);
          const Vec3 normal = (camera.target - camera.Eye()).normalized();
          const auto [o, r] = MouseRay(camera, d[2], d[3], panel, scene_width, fb_height);
          sim.Drag(o + r * ((hit->point - o).dot(normal) / r.dot(normal)));
        } else {
          std::cerr << "gipsi: --drag: nothing that can be pulled under the mouse at " << d[0]
                    << ", " << d[1] << "\n";
        }
        sim.RunUntil(options.screenshot_time);
        scripted_drag_done = true;
      }
      if (dragging_tool && !ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
        sim.ReleaseTool();
        dragging_tool = false;
      }
      if (dragging_haptic && !ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
        sim.HapticEndDrag();
        dragging_haptic = false;
      }

      if (options.show_ui) {
        ImGui::SetNextWindowPos(ImVec2(0, 0));
        ImGui::SetNextWindowSize(ImVec2(float(panel / scale), float(fb_height / scale)));
        ImGui::Begin(
            "GiPSi", nullptr,
            ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
        ImGui::Text("t = %.4f / %.4g s%s", status.time, status.end_time,
                    status.at_end ? " (end)" : "");
        ImGui::Text("real-time factor %.3g", status.real_time_factor);
        if (ImGui::Button(status.playing ? "Pause" : "Play")) sim.SetPlaying(!status.playing);
        ImGui::SameLine();
        if (ImGui::Button("Step")) sim.Step();
        ImGui::SameLine();
        if (ImGui::Button("Reset")) sim.Reset();
        if (ImGui::Checkbox("as fast as possible", &as_fast_as_possible) ||
            ImGui::SliderFloat("speed", &speed, 0.01f, 10.0f, "%.3g x real time",
                               ImGuiSliderFlags_Logarithmic))
          sim.SetSpeed(as_fast_as_possible ? 0.0 : double(speed));
        if (ImGui::Combo("at the end", &at_end, "pause\0loop\0continue\0"))
          sim.SetAtEnd(static_cast<AtEnd>(at_end));
        if (!status.message.empty())
          ImGui::TextColored(ImVec4(0.8f, 0.1f, 0.1f, 1), "%s", status.message.c_str());
        ImGui::Separator();
        ImGui::Checkbox("wireframe (all)", &render.wireframe);
        ImGui::SameLine();
        ImGui::Checkbox("lighting", &render.lighting);
        for (std::size_t i = 0; i < ui.size() && i < status.objects.size(); ++i) {
          const std::string& name = status.objects[i].name;
          const auto& fields = status.objects[i].fields;
          ImGui::PushID(static_cast<int>(i));
          ImGui::Checkbox(name.c_str(), &ui[i].visible);
          if (i < frame.surfaces.size() && frame.surfaces[i].primitive == Primitive::kTriangles) {
            ImGui::SameLine();
            ImGui::Checkbox("edges", &ui[i].wireframe);
          }
          std::string items = std::string("(solid)") + '\0';
          for (const auto& f : fields) items += f + '\0';
          bool changed = ImGui::Combo("field", &ui[i].field, items.c_str());
          if (ui[i].field > 0) {
            // Scalars (V, pressure) have no component box: they are drawn as their value.
            const auto choices =
                ComponentChoices(status.objects[i].components[std::size_t(ui[i].field - 1)]);
            if (ui[i].component >= static_cast<int>(choices.size())) ui[i].component = 0;
            if (!choices.empty()) {
              std::string component_items;
              for (const auto& c : choices) component_items += c + '\0';
              changed |= ImGui::Combo("component", &ui[i].component, component_items.c_str());
            }
            std::string map_items;
            for (const auto& m : maps) map_items += m + '\0';
            changed |= ImGui::Combo("map", &ui[i].map, map_items.c_str());
          }
          if (changed) {
            ColorSpec spec;
            if (ui[i].field > 0) {
              spec.field = fields[std::size_t(ui[i].field - 1)];
              spec.component = ui[i].component - 1;
              spec.color_map = maps[std::size_t(ui[i].map)];
            }
            sim.SetColor(i, spec);
          }
          if (i < frame.surfaces.size() && !frame.surfaces[i].color_map.empty()) {
            const SurfaceBuffers& s = frame.surfaces[i];
            ImGui::Text("%s [%s]", s.field.c_str(), s.units.c_str());
            const ColorMap map = ColorMap::Named(s.color_map);
            const ImVec2 p = ImGui::GetCursorScreenPos();
            const float w = ImGui::GetContentRegionAvail().x, h = 14;
            for (int k = 0; k < 32; ++k) {
              const Rgb a = map.At(k / 32.0), b = map.At((k + 1) / 32.0);
              ImGui::GetWindowDrawList()->AddRectFilledMultiColor(
                  ImVec2(p.x + w * k / 32, p.y), ImVec2(p.x + w * (k + 1) / 32, p.y + h),
                  ImGui::GetColorU32(ImVec4(a.r, a.g, a.b, 1)),
                  ImGui::GetColorU32(ImVec4(b.r, b.g, b.b, 1)),
                  ImGui::GetColorU32(ImVec4(b.r, b.g, b.b, 1)),
                  ImGui::GetColorU32(ImVec4(a.r, a.g, a.b, 1)));
            }
            ImGui::Dummy(ImVec2(w, h));
            if (s.num_no_data == s.num_vertices()) {  // e.g. no activation time anywhere yet
              ImGui::Text("not yet");
            } else {
              ImGui::Text("%.4g", s.range_lo);
              ImGui::SameLine(std::max(1.0f, w - 60));
              ImGui::Text("%.4g", s.range_hi);
              if (s.num_no_data > 0) ImGui::TextDisabled("grey: not yet");
            }
          }
          ImGui::PopID();
        }
        ImGui::Separator();
        if (status.haptic_mouse) {
          ImGui::TextWrapped(
              "Mouse: left drag orbits, right drag pans, wheel zooms; Ctrl (or Shift) + left "
              "drag moves the haptic tool in the plane facing you, Ctrl + wheel pushes it "
              "into the scene or pulls it back.");
          if (const auto tool = sim.HapticTool())
            ImGui::Text("tool at (%.4g, %.4g, %.4g) m\nforce %.3g N", tool->first.x(),
                        tool->first.y(), tool->first.z(), tool->second.norm());
        } else if (any_pullable) {
          ImGui::TextWrapped(
              "Mouse: left drag orbits, right drag pans, wheel zooms; Ctrl (or Shift) + left "
              "drag pulls the tissue.");
        } else {
          ImGui::TextWrapped("Mouse: left drag orbits, right drag pans, wheel zooms.");
        }
        if (!frame.traces.empty()) {
          ImGui::Separator();
          std::vector<float> shown;
          for (const ProbeTrace& trace : frame.traces)
            for (std::size_t c = 0; c < trace.columns.size(); ++c) {
              const auto& v = trace.values[c];
              if (v.empty()) continue;
              // In the scene's display units, labelled above the curve (not over it); a
              // no-data marker (e.g. -1 for "not activated yet") is a gap, not a value.
              const double scale = c < trace.scales.size() ? trace.scales[c] : 1.0;
              const double marker = c < trace.no_data.size() ? trace.no_data[c] : NAN;
              shown.resize(v.size());
              for (std::size_t k = 0; k < v.size(); ++k)
                shown[k] = v[k] == float(marker) ? NAN : float(scale * v[k]);
              const std::string label =
                  c < trace.labels.size() ? trace.labels[c] : trace.columns[c];
              const std::string unit = c < trace.units.size() ? trace.units[c] : "";
              const std::string value =
                  std::isnan(shown.back())
                      ? std::string(v.back() == float(marker) ? "not yet" : "-")
                      : fmt::format("{:.4g}{}{}", shown.back(), unit.empty() ? "" : " ", unit);
              ImGui::Text("%s: %s", label.c_str(), value.c_str());
              ImGui::PlotLines(("##" + trace.name + "." + trace.columns[c]).c_str(), shown.data(),
                               static_cast<int>(shown.size()), 0, nullptr, FLT_MAX, FLT_MAX,
                               ImVec2(ImGui::GetContentRegionAvail().x, 40));
            }
        }
        ImGui::End();
      }

      render.viewport_x = panel;
      // The haptic tool, drawn over a copy of the frame: a 12-pixel point, black while it
      // feels nothing, red while a force is commanded to it.
      const FrameBuffers* drawn = &frame;
      FrameBuffers with_tool;
      if (status.haptic_mouse && frame.frame >= 0)
        if (const auto tool = sim.HapticTool()) {
          with_tool = frame;
          with_tool.surfaces.push_back(HapticToolPoint(tool->first, tool->second));
          drawn = &with_tool;
        }
      renderer.Draw(*drawn, camera, scene_width, fb_height, render);
      ImGui::Render();
      gl.Viewport(0, 0, fb_width, fb_height);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

      if (!options.screenshot.empty() && status.failed) {  // (the message is on stderr already)
        exit_code = 3;
        break;
      }
      if (!options.screenshot.empty() && scripted_drag_done && frame.frame >= 0 &&
          frame.time >= options.screenshot_time - 1e-12 && ++frames_at_screenshot_time >= 3) {
        // A few frames after the time is reached, so the camera and panels have settled.
        const Image image = ReadBackBuffer(gl, fb_width, fb_height);
        try {
          WritePng(image, options.screenshot);
          std::cout << fmt::format("{}: {} x {} at t = {:.6g} s ({})\n", options.screenshot,
                                   image.width, image.height, frame.time,
                                   reinterpret_cast<const char*>(gl.GetString(GL_RENDERER)));
          if (!status.pull_object.empty())
            std::cout << fmt::format("mouse pull on '{}': force {:.6g} N (cap {:.6g} N)\n",
                                     status.pull_object, status.pull_force, status.pull_max_force);
          if (const auto tool = sim.HapticTool())
            std::cout << fmt::format(
                "haptic tool at ({:.9g}, {:.9g}, {:.9g}) m, force ({:.9g}, {:.9g}, {:.9g}) N\n",
                tool->first.x(), tool->first.y(), tool->first.z(), tool->second.x(),
                tool->second.y(), tool->second.z());
        } catch (const std::exception& e) {
          std::cerr << "gipsi: error: " << e.what() << "\n";
          exit_code = 4;
        }
        break;
      }
      glfwSwapBuffers(window);
      // Without vsync (e.g. under Xvfb) keep to about 60 frames a second.
      std::this_thread::sleep_until(frame_start + std::chrono::microseconds(16000));
    }
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
  return exit_code;
}

}  // namespace gipsi::viz
