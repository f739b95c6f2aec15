#include "net_drawing.hpp"

#include <graphviz/cgraph.h>
#include <graphviz/gvc.h>

#include <map>
#include <mutex>
#include <vector>

#include "tripodal/core/net_dot.hpp"

namespace tripodal::monitor {
namespace {

// One Graphviz context for the process, never freed: libgvc 2.42's text-size code keeps a font
// name across contexts, so a context made after another was freed reads freed memory (AddressSanitizer
// shows it in textspan_size). Graphviz is not thread-safe either: one drawing at a time.
GVC_t* graphviz() {
  static GVC_t* const context = gvContext();
  return context;
}
std::mutex graphviz_mutex;

}  // namespace

struct NetDrawing::Impl {
  std::map<std::string, std::string, std::less<>> cache;
};

NetDrawing::NetDrawing() : impl_(std::make_unique<Impl>()) {}
NetDrawing::~NetDrawing() = default;

const std::string& NetDrawing::svg(const PetriNet& net) {
  std::string out;
  // The drawing of `tripodal-net dot` without its legend, every place empty: the page marks the
  // places of the live marking.
  const std::vector<Tokens> empty(net.places().size(), 0);
  // The page titles each drawing itself; the net's description (a plan's whole text) would make
  // the drawing as wide as that line.
  PetriNet untitled = net;
  untitled.description.clear();
  const std::string text = net_to_dot(untitled, empty, DotOptions{.descriptions = false});
  // Keyed by the drawing's text, not the net's id: an edited net reloaded under the same id and
  // file name is drawn anew. Writing the text costs little next to Graphviz's layout.
  if (const auto it = impl_->cache.find(text); it != impl_->cache.end()) return it->second;
  const std::lock_guard lock(graphviz_mutex);
  GVC_t* gvc = graphviz();
  if (Agraph_t* g = agmemread(text.c_str())) {
    if (gvLayout(gvc, g, "dot") == 0) {
      char* data = nullptr;
      unsigned int length = 0;
      if (gvRenderData(gvc, g, "svg", &data, &length) == 0 && data != nullptr) {
        out.assign(data, length);
        // The page embeds the drawing: the XML prologue and DOCTYPE are not wanted there.
        if (const std::size_t start = out.find("<svg"); start != std::string::npos) out.erase(0, start);
      }
      gvFreeRenderData(data);
      gvFreeLayout(gvc, g);
    }
    agclose(g);
  }
  return impl_->cache.emplace(text, std::move(out)).first->second;
}

}  // namespace tripodal::monitor
