#pragma once
// One pipeline stage: items handed to it are processed by its handler either at once on the
// caller's thread (inline: one fixed order, byte-identical outputs with pipeline.threads = 1)
// or on the stage's own thread behind a bounded queue. The Mapper makes the same calls in both
// modes, so the sequential and the threaded pipeline are one code path.
//
// Thread safety: push/try_push/push_drop_oldest/close from one producer thread.
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "pipeline/bounded_queue.hpp"

namespace semap {

template <class Item>
class Stage {
 public:
  using Handler = std::function<void(Item&)>;
  /// `on_close` runs after the last item (on the stage's thread), e.g. to flush held work.
  Stage(bool threaded, size_t capacity, Handler handler, std::function<void()> on_close = {})
      : threaded_(threaded), queue_(capacity), handler_(std::move(handler)), on_close_(std::move(on_close)) {
    if (threaded_) worker_ = std::thread([this] { run(); });
  }
  ~Stage() {
    queue_.close();
    if (worker_.joinable()) worker_.join();
  }
  Stage(const Stage&) = delete;
  Stage& operator=(const Stage&) = delete;

  /// Hands an item over; blocks while the queue is full. Rethrows a handler's exception (inline:
  /// at once; threaded: at the next call).
  void push(Item item) {
    rethrow_failure();
    if (!threaded_) return handler_(item);
    queue_.push(std::move(item));
  }
  /// Hands an item over unless the queue is full (then returns false and `item` is untouched).
  bool try_push(Item& item) {
    rethrow_failure();
    if (!threaded_) {
      handler_(item);
      return true;
    }
    return queue_.try_push(std::move(item));
  }
  /// Hands an item over; when the queue is full its oldest waiting item is removed and returned.
  std::optional<Item> push_drop_oldest(Item item) {
    rethrow_failure();
    if (!threaded_) {
      handler_(item);
      return std::nullopt;
    }
    return queue_.push_drop_oldest(std::move(item));
  }
  /// No more items: waits until every item is processed and on_close ran. Rethrows the first
  /// exception a handler threw. Idempotent.
  void close() {
    if (!closed_) {
      closed_ = true;
      queue_.close();
      if (worker_.joinable()) worker_.join();
      if (!threaded_ && on_close_) on_close_();
    }
    rethrow_failure();
  }
  size_t capacity() const { return queue_.capacity(); }

 private:
  void run() {
    while (auto item = queue_.pop()) handle(*item);
    if (on_close_) guarded(on_close_);
  }
  void handle(Item& item) {
    guarded([&] { handler_(item); });
  }
  /// After a failure the remaining items are drained unprocessed; the error reaches the producer.
  template <class F>
  void guarded(F&& f) {
    {
      std::lock_guard lock(failure_mutex_);
      if (failure_) return;
    }
    try {
      f();
    } catch (...) {
      std::lock_guard lock(failure_mutex_);
      if (!failure_) failure_ = std::current_exception();
    }
  }
  void rethrow_failure() {
    std::exception_ptr failure;
    {
      std::lock_guard lock(failure_mutex_);
      failure = failure_;
    }
    if (failure) std::rethrow_exception(failure);
  }

  const bool threaded_;
  BoundedQueue<Item> queue_;
  Handler handler_;
  std::function<void()> on_close_;
  std::thread worker_;
  bool closed_ = false;
  std::mutex failure_mutex_;
  std::exception_ptr failure_;
};

}  // namespace semap
