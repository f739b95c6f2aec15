// Draws a Petri net like the paper's figures (core's net_to_dot, as `tripodal-net dot` does) laid out
// by Graphviz's library (libgvc) into SVG, which the monitor page marks live: each node's <title> is
// its place or transition id. Private to the monitor.
#pragma once

#include <memory>
#include <string>

#include "tripodal/core/petri_net.hpp"

namespace tripodal::monitor {

class NetDrawing final {
 public:
  NetDrawing();
  ~NetDrawing();
  NetDrawing(const NetDrawing&) = delete;
  NetDrawing& operator=(const NetDrawing&) = delete;

  /// The SVG of `net`; nets drawn before (the same drawing text) come from this drawing's cache.
  /// Drawings in several threads take turns (Graphviz is not thread-safe).
  const std::string& svg(const PetriNet& net);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal::monitor
