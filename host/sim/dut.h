// SPDX-License-Identifier: MIT
// Uniform cycle steppers over a Verilated module and over its golden model.
//
// A port adaptor P describes one RTL module and its model:
//   using Rtl = V<module>; using Model = ...; using In = ...; using Out = ...;
//   static void drive(Rtl&, const In&);   // copy the inputs onto the pins
//   static Out sample(const Rtl&);        // read the outputs off the pins
//   static std::vector<Field<Out>> fields();  // every output, named, for comparison
//   static typename Model::Params model_params();  // the configuration Rtl was built with
// Each stepper's step(in) applies the inputs for one clock cycle, returns the
// outputs as they settle before the rising edge, then applies the edge.
#pragma once

#include <verilated.h>
#include <verilated_fst_c.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace cpstep::sim {

template <class Out>
struct Field {
  const char* name;
  uint64_t (*get)(const Out&);
};

// The seed of the next RtlDut whose port adaptor asks for random initial values
// (P::kRandomInit: a Verilated build with --x-initial unique); each such DUT takes
// the current value and advances it, so runs are repeatable from the first seed.
inline uint64_t& random_init_seed_state() {
  thread_local uint64_t seed = 1;
  return seed;
}
inline uint64_t random_init_seed() { return random_init_seed_state()++; }

template <class P>
class RtlDut {
 public:
  // trace_path: write an FST waveform of every signal there ("" for none).
  explicit RtlDut(const std::string& trace_path = "") : ctx_(std::make_unique<VerilatedContext>()) {
    ctx_->traceEverOn(!trace_path.empty());
    // A build with random initial values (rtl/CMakeLists.txt XINIT) seeded per DUT.
    if constexpr (requires { P::kRandomInit; }) {
      ctx_->randReset(2);
      ctx_->randSeed(int(random_init_seed()));
    }
    rtl_ = std::make_unique<typename P::Rtl>(ctx_.get(), "top");
    if (!trace_path.empty()) {
      // (a build without tracing compiled in, as scripts/bench-verilator's, has no trace())
      if constexpr (requires(VerilatedFstC* t) { rtl_->trace(t, 99); }) {
        trace_ = std::make_unique<VerilatedFstC>();
        rtl_->trace(trace_.get(), 99);
        trace_->open(trace_path.c_str());
      } else {
        throw std::invalid_argument("this Verilated build has no tracing: no waveform for " + trace_path);
      }
    }
    rtl_->clk = 0;
  }
  ~RtlDut() {
    if (trace_) trace_->close();
    rtl_->final();
  }
  RtlDut(const RtlDut&) = delete;
  RtlDut& operator=(const RtlDut&) = delete;

  typename P::Out step(const typename P::In& in) {
    rtl_->clk = 0;
    P::drive(*rtl_, in);
    rtl_->eval();
    const typename P::Out out = P::sample(*rtl_);
    if (trace_) trace_->dump(2 * cycle_);
    rtl_->clk = 1;
    rtl_->eval();
    if (trace_) trace_->dump(2 * cycle_ + 1);
    ++cycle_;
    return out;
  }
  uint64_t cycle() const { return cycle_; }
  typename P::Rtl& rtl() { return *rtl_; }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<typename P::Rtl> rtl_;
  std::unique_ptr<VerilatedFstC> trace_;
  uint64_t cycle_ = 0;
};

template <class P>
class ModelDut {
 public:
  explicit ModelDut(typename P::Model::Params params = P::model_params()) : model_(params) {}
  typename P::Out step(const typename P::In& in) {
    model_.in = in;
    const typename P::Out out = model_.outputs();
    model_.tick();
    ++cycle_;
    return out;
  }
  uint64_t cycle() const { return cycle_; }
  typename P::Model& model() { return model_; }

 private:
  typename P::Model model_;
  uint64_t cycle_ = 0;
};

// ModelDut with event skipping, for the lockstep benches that prove it: when the
// model says the coming clocks are quiet (Model::quiet_for: nothing but counters
// changes and no output moves while the inputs stay), it only counts them while
// the inputs stay the same as far as P::held_equal tells, and applies them at
// once (Model::skip) when the inputs change or the quiet ends. Meanwhile the
// outputs come from the model not yet advanced, for the inputs of the cycle:
// quiet means they are the advanced model's too (P::held_equal may let through
// inputs that only choose what an output shows, like a read port's address).
template <class P>
class SkippingModelDut {
 public:
  explicit SkippingModelDut(typename P::Model::Params params = P::model_params()) : model_(params) {}
  typename P::Out step(const typename P::In& in) {
    ++cycle_;
    if (left_ > 0 && P::held_equal(held_, in)) {
      --left_;
      ++pending_;
      model_.in = in;
      return model_.outputs();
    }
    catch_up();
    model_.in = in;
    const typename P::Out out = model_.outputs();
    if (const uint64_t h = model_.quiet_for(kMaxSkip)) {
      held_ = in;
      pending_ = 1;
      left_ = h - 1;
      skipped_ += h;
    } else {
      model_.tick();
    }
    return out;
  }
  uint64_t cycle() const { return cycle_; }
  // Clocks the model advanced by skip() rather than tick().
  uint64_t skipped() const { return skipped_; }
  typename P::Model& model() {
    catch_up();
    return model_;
  }

 private:
  static constexpr uint64_t kMaxSkip = uint64_t(1) << 40;
  void catch_up() {
    if (pending_) model_.skip(pending_);
    skipped_ -= left_;
    pending_ = left_ = 0;
  }
  typename P::Model model_;
  typename P::In held_{};
  uint64_t cycle_ = 0, pending_ = 0, left_ = 0, skipped_ = 0;
};

// The model stepper a lockstep bench runs against the RTL: P::ModelStepper when
// the port names one (e.g. SkippingModelDut<P>), else ModelDut<P>.
template <class P>
struct ModelStepperOf {
  using type = ModelDut<P>;
};
template <class P>
  requires requires { typename P::ModelStepper; }
struct ModelStepperOf<P> {
  using type = typename P::ModelStepper;
};

}  // namespace cpstep::sim
