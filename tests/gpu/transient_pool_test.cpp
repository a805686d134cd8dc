// gpu::TransientPool: sizes, reuse (preferred ids first, then best fit within
// the slack), accounting, trimming, two threads leasing at once, and a
// leased buffer used by the device.
#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <map>
#include <mutex>
#include <numeric>
#include <random>
#include <set>
#include <thread>

#include "dn/shaders/shaders.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu/error.hpp"
#include "gpu/transient_pool.hpp"
#include "gpu_test_env.hpp"
#include "kernel_runner.hpp"

namespace dn {
namespace {

using gpu::TransientPool;
using namespace std::chrono_literals;

class TransientPoolTest : public test::GpuTest {};

TEST_F(TransientPoolTest, LeasesDistinctBuffersOfAtLeastTheSizes) {
  TransientPool pool(ctx());
  const std::vector<uint64_t> sizes = {1000, 5000, 1, 5000};
  auto lease = pool.lease(sizes);
  ASSERT_EQ(lease.size(), sizes.size());
  std::set<VkBuffer> handles;
  std::set<uint64_t> ids;
  for (size_t i = 0; i < sizes.size(); ++i) {
    EXPECT_GE(lease.buffer(i).size(), sizes[i]);
    EXPECT_EQ(lease.buffer(i).size() % 256, 0u) << "rounded to the granularity";
    EXPECT_EQ(lease.buffer(i).kind(), gpu::BufferKind::Storage);
    handles.insert(lease.handle(i));
    ids.insert(lease.id(i));
  }
  EXPECT_EQ(handles.size(), sizes.size());
  EXPECT_EQ(ids.size(), sizes.size());
  EXPECT_THROW(lease.buffer(4), gpu::Error);
  const uint64_t zero[] = {0};
  EXPECT_THROW(pool.lease(zero), gpu::Error);
  EXPECT_TRUE(pool.lease({}).empty());
}

TEST_F(TransientPoolTest, AccountingFollowsLeasesAndReturns) {
  TransientPool pool(ctx());
  const uint64_t sizes[] = {4096, 1000};
  {
    auto lease = pool.lease(sizes);
    const auto s = pool.stats();
    EXPECT_EQ(s.buffers, 2u);
    EXPECT_EQ(s.buffers_in_use, 2u);
    EXPECT_EQ(s.allocated_bytes, 4096u + 1024u);
    EXPECT_EQ(s.in_use_bytes, 4096u + 1024u);
    EXPECT_EQ(s.requested_bytes, 5096u);
    EXPECT_EQ(s.created, 2u);
    EXPECT_EQ(s.reused, 0u);
  }
  auto s = pool.stats();
  EXPECT_EQ(s.buffers, 2u);
  EXPECT_EQ(s.buffers_in_use, 0u);
  EXPECT_EQ(s.allocated_bytes, 5120u);
  EXPECT_EQ(s.in_use_bytes, 0u);
  EXPECT_EQ(s.requested_bytes, 0u);

  // Moving a lease moves the obligation to return it, once.
  auto a = pool.lease(sizes);
  TransientPool::Lease b = std::move(a);
  EXPECT_TRUE(a.empty());
  a.release();
  EXPECT_EQ(pool.stats().buffers_in_use, 2u);
  b.release();
  b.release();
  s = pool.stats();
  EXPECT_EQ(s.buffers_in_use, 0u);
  EXPECT_EQ(s.reused, 2u);
  EXPECT_EQ(s.created, 2u);
}

TEST_F(TransientPoolTest, ReturnedBuffersAreReusedPreferredFirst) {
  TransientPool pool(ctx());
  const uint64_t sizes[] = {8192, 8192, 8192};
  std::vector<uint64_t> first;
  {
    auto lease = pool.lease(sizes);
    first = lease.ids();
  }
  {
    // Preferred ids come back in the slots asked for, whatever their order.
    const std::vector<uint64_t> rotated = {first[2], first[0], first[1]};
    auto lease = pool.lease(sizes, rotated);
    EXPECT_EQ(lease.ids(), rotated);
  }
  {
    const auto ids = pool.lease(sizes).ids();
    EXPECT_EQ(std::set<uint64_t>(ids.begin(), ids.end()), std::set<uint64_t>(first.begin(), first.end()));
  }
  EXPECT_EQ(pool.stats().created, 3u);
  EXPECT_EQ(pool.stats().allocated_bytes, 3u * 8192);
  // A preferred id that no longer fits (or is unknown) is ignored.
  const uint64_t bigger[] = {16384};
  const uint64_t prefer[] = {first[0]};
  auto lease = pool.lease(bigger, prefer);
  EXPECT_NE(lease.id(0), first[0]);
  EXPECT_GE(lease.buffer(0).size(), 16384u);
}

TEST_F(TransientPoolTest, BestFitWithinTheSlack) {
  TransientPool pool(ctx());
  std::map<uint64_t, uint64_t> id_of_size;
  {
    const uint64_t sizes[] = {4096, 8192, 65536};
    auto lease = pool.lease(sizes);
    for (size_t i = 0; i < 3; ++i) id_of_size[sizes[i]] = lease.id(i);
  }
  {
    const uint64_t want[] = {5000};  // 8192 fits best (65536 fits too)
    EXPECT_EQ(pool.lease(want).id(0), id_of_size[8192]);
  }
  {
    const uint64_t want[] = {40000};  // 65536 is at most twice as large
    EXPECT_EQ(pool.lease(want).id(0), id_of_size[65536]);
  }
  {
    const uint64_t want[] = {1000};  // 4096 is more than twice as large: a new buffer
    auto lease = pool.lease(want);
    for (const auto& [size, id] : id_of_size) EXPECT_NE(lease.id(0), id);
    EXPECT_EQ(lease.buffer(0).size(), 1024u);
  }
  {
    // Largest first: 8192 must not go to the 5000 slot when the 7000 slot
    // fits nothing else (4096 too small, 65536 too large for either).
    const uint64_t want[] = {5000, 7000};
    auto lease = pool.lease(want);
    EXPECT_EQ(lease.id(1), id_of_size[8192]);
    EXPECT_NE(lease.id(0), id_of_size[65536]);
  }
}

TEST_F(TransientPoolTest, TrimFreesBuffersIdleLongEnoughAndNeverLeasedOnes) {
  TransientPool pool(ctx());
  const uint64_t sizes[] = {4096, 4096};
  { auto returned = pool.lease(sizes); }
  const auto returned_at = TransientPool::Clock::now();
  const uint64_t one[] = {100000};
  auto held = pool.lease(one);
  EXPECT_EQ(pool.trim(10s, returned_at + 5s), 0u) << "returned 5 s ago, idle limit 10 s";
  EXPECT_EQ(pool.stats().buffers, 3u);
  EXPECT_EQ(pool.trim(10s, returned_at + 20s), 8192u);
  auto s = pool.stats();
  EXPECT_EQ(s.buffers, 1u);
  EXPECT_EQ(s.allocated_bytes, held.buffer(0).size());
  EXPECT_EQ(s.trimmed_bytes, 8192u);
  EXPECT_EQ(pool.trim(0s), 0u) << "a leased buffer is never trimmed";
  held.release();
  EXPECT_EQ(pool.trim(0s), 100096u);
  EXPECT_EQ(pool.stats().allocated_bytes, 0u);
  // After a trim, leasing allocates anew.
  auto again = pool.lease(sizes);
  EXPECT_EQ(pool.stats().created, 5u);
}

TEST_F(TransientPoolTest, TwoThreadsNeverHoldTheSameBuffer) {
  TransientPool pool(ctx());
  std::mutex mutex;
  std::set<uint64_t> held;  // ids leased right now, by either thread
  std::atomic<int> overlaps{0};
  auto worker = [&](uint32_t seed) {
    std::mt19937 rng(seed);
    const uint64_t choices[] = {1024, 3000, 4096, 20000};
    std::vector<uint64_t> previous;
    for (int iter = 0; iter < 300; ++iter) {
      std::vector<uint64_t> sizes(1 + rng() % 3);
      for (auto& s : sizes) s = choices[rng() % 4];
      auto lease = pool.lease(sizes, previous);
      {
        std::lock_guard lock(mutex);
        for (size_t i = 0; i < lease.size(); ++i) {
          if (!held.insert(lease.id(i)).second) ++overlaps;
          if (lease.buffer(i).size() < sizes[i]) ++overlaps;
        }
      }
      std::this_thread::yield();
      {
        std::lock_guard lock(mutex);
        for (size_t i = 0; i < lease.size(); ++i) held.erase(lease.id(i));
      }
      previous = lease.ids();
      if (iter % 50 == 49) pool.trim(0s);  // trimming while the other thread leases
    }
  };
  std::thread a(worker, 1), b(worker, 2);
  a.join();
  b.join();
  EXPECT_EQ(overlaps.load(), 0);
  const auto s = pool.stats();
  EXPECT_EQ(s.buffers_in_use, 0u);
  EXPECT_EQ(s.in_use_bytes, 0u);
  EXPECT_EQ(s.requested_bytes, 0u);
  EXPECT_GT(s.reused, 0u);
  EXPECT_EQ(pool.trim(0s), s.allocated_bytes);
  EXPECT_EQ(pool.stats().buffers, 0u);
}

TEST_F(TransientPoolTest, LeasedBuffersAreDeviceStorage) {
  gpu::TransientPool& pool = TransientPool::of(ctx());
  EXPECT_EQ(&pool, &TransientPool::of(ctx())) << "one pool per context";
  const uint64_t bytes = 4000;
  std::vector<uint8_t> data(bytes);
  std::iota(data.begin(), data.end(), uint8_t{7});
  gpu::Buffer in(ctx(), bytes, gpu::BufferKind::StorageUpload, "in");
  gpu::Buffer out(ctx(), bytes, gpu::BufferKind::StorageDownload, "out");
  in.write(data);
  const uint64_t sizes[] = {bytes};
  auto lease = pool.lease(sizes);
  gpu::CommandStream stream(ctx());
  VkCommandBuffer cmd = stream.begin();
  in.record_upload(cmd, bytes);
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_TRANSFER_READ_BIT);
  const VkBufferCopy copy{0, 0, bytes};
  vkCmdCopyBuffer(cmd, in.handle(), lease.handle(0), 1, &copy);
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_TRANSFER_READ_BIT);
  vkCmdCopyBuffer(cmd, lease.handle(0), out.handle(), 1, &copy);
  out.record_readback(cmd, bytes, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
  stream.submit_and_wait();
  lease.release();  // after the work completed
  std::vector<uint8_t> back(bytes);
  out.read(back);
  EXPECT_EQ(back, data);
  pool.trim(0s);
}

// The pattern a pipeline follows (see transient_pool.hpp): lease per frame
// with last frame's ids preferred, rewrite the descriptor set only when the
// ids changed, return the lease after the submission completed. Frame 1
// finds frame 0's buffers held by another session and must rewrite; frame 2
// gets frame 1's again and need not.
TEST_F(TransientPoolTest, DescriptorSetsFollowTheLeasedBuffers) {
  TransientPool pool(ctx());
  const uint32_t w = 21, h = 13;
  const uint64_t plane = uint64_t{w} * h * 16;
  auto kernel = ctx().kernels().get(test::grid_kernel_desc("tile_probe", shaders::get("tile_probe"), 3, 8, {{1, 2}}));
  gpu::Buffer uniform(ctx(), 256, gpu::BufferKind::Constants, "unused");
  gpu::DescriptorPool descriptors(ctx(), 1, 3);
  VkDescriptorSet set = VK_NULL_HANDLE;
  std::vector<uint64_t> held;
  const uint64_t sizes[] = {plane, plane};
  int rewrites = 0;
  // Persistent buffers (inputs, outputs) stay; only the transient ones move.
  gpu::Buffer source(ctx(), plane, gpu::BufferKind::StorageUpload, "source");
  gpu::Buffer result(ctx(), plane, gpu::BufferKind::StorageDownload, "result");
  for (int frame = 0; frame < 3; ++frame) {
    SCOPED_TRACE(testing::Message() << "frame " << frame);
    std::vector<std::array<float, 4>> input(size_t{w} * h);  // exact through a radius-0 gather
    for (size_t i = 0; i < input.size(); ++i) input[i] = {float(i), float(frame), 1.0f, -float(i)};
    source.write({reinterpret_cast<const uint8_t*>(input.data()), plane});
    TransientPool::Lease other;
    if (frame == 1) other = pool.lease(sizes);  // another session holds last frame's buffers
    auto lease = pool.lease(sizes, held);
    const VkBuffer storage[] = {source.handle(), lease.handle(0), lease.handle(1)};
    if (!set) {
      set = descriptors.allocate(*kernel, uniform.handle(), storage);
    } else if (lease.ids() != held) {
      descriptors.write(set, *kernel, uniform.handle(), storage);
      ++rewrites;
    }
    held = lease.ids();

    gpu::CommandStream stream(ctx());
    VkCommandBuffer cmd = stream.begin();
    source.record_upload(cmd, plane);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
    gpu::GridPush grid = test::grid(w, h);  // R = 0: clamped = source
    grid.args[1] = std::bit_cast<uint32_t>(1.0f);
    kernel->record_dispatch(cmd, set, grid);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
    const VkBufferCopy copy{0, 0, plane};
    vkCmdCopyBuffer(cmd, lease.handle(0), result.handle(), 1, &copy);
    result.record_readback(cmd, plane, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    stream.submit_and_wait();
    lease.release();
    using Vec4 = std::array<float, 4>;
    EXPECT_EQ(test::read<Vec4>(result), input);
  }
  EXPECT_EQ(rewrites, 1);
  EXPECT_EQ(pool.stats().created, 4u);
}

}  // namespace
}  // namespace dn
