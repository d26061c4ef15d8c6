#include "groundslam/core/NearestDescriptors.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#if defined(__x86_64__) || defined(_M_X64)
#define GROUNDSLAM_X86 1
#include <immintrin.h>
#endif

#include "groundslam/core/Hamming.hpp"

namespace groundslam {
namespace {

constexpr int kWords = 4;  // 64-bit words of a 256-bit descriptor

/// Train descriptors word by word (all first words, then all second words, ...), padded with zeros to whole
/// blocks of eight, so that one vector load brings the same word of consecutive descriptors.
struct TransposedTrain {
  explicit TransposedTrain(const cv::Mat& train) : rows(train.rows), padded((train.rows + 7) / 8 * 8) {
    words.assign(static_cast<size_t>(kWords * padded), 0);
    for (int t = 0; t < rows; ++t) {
      std::uint64_t w[kWords];
      std::memcpy(w, train.ptr<std::uint8_t>(t), sizeof(w));
      for (int k = 0; k < kWords; ++k) words[static_cast<size_t>(k * padded + t)] = w[k];
    }
  }
  const std::uint64_t* word(int k) const { return words.data() + static_cast<size_t>(k * padded); }
  int rows, padded;
  std::vector<std::uint64_t> words;
};

/// Merges per-lane results (each lane: the nearest and second nearest of its own train rows) into one.
TwoNearest mergeLanes(const std::int64_t* best, const std::int64_t* index, const std::int64_t* second, int lanes) {
  int winner = -1;
  for (int l = 0; l < lanes; ++l) {
    if (index[l] < 0) continue;
    if (winner < 0 || best[l] < best[winner] || (best[l] == best[winner] && index[l] < index[winner])) winner = l;
  }
  TwoNearest r;
  if (winner < 0) return r;
  r.best = static_cast<int>(index[winner]);
  r.best_distance = static_cast<int>(best[winner]);
  std::int64_t second_distance = second[winner];
  for (int l = 0; l < lanes; ++l) {
    if (l != winner && index[l] >= 0) second_distance = std::min(second_distance, best[l]);
  }
  r.second_distance = static_cast<int>(second_distance);
  return r;
}

void scalarKernel(const cv::Mat& query, const cv::Mat& train, std::vector<TwoNearest>& out) {
  for (int q = 0; q < query.rows; ++q) {
    const std::uint8_t* descriptor = query.ptr<std::uint8_t>(q);
    TwoNearest& r = out[static_cast<size_t>(q)];
    for (int t = 0; t < train.rows; ++t) {
      const int d = hammingDistance256(descriptor, train.ptr<std::uint8_t>(t));
      if (d < r.best_distance) {
        r.second_distance = r.best_distance;
        r.best_distance = d, r.best = t;
      } else if (d < r.second_distance) {
        r.second_distance = d;
      }
    }
  }
}

#ifdef GROUNDSLAM_X86

__attribute__((target("avx2"))) void avx2Kernel(const cv::Mat& query, const TransposedTrain& train, std::vector<TwoNearest>& out) {
  // Popcount of each byte by two 4-bit table lookups, bytes summed per 64-bit lane: four distances at once.
  const __m256i table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4, 0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i low = _mm256_set1_epi8(0x0f), none = _mm256_set1_epi64x(257), last = _mm256_set1_epi64x(train.rows - 1);
  for (int q = 0; q < query.rows; ++q) {
    std::uint64_t w[kWords];
    std::memcpy(w, query.ptr<std::uint8_t>(q), sizeof(w));
    __m256i qw[kWords];
    for (int k = 0; k < kWords; ++k) qw[k] = _mm256_set1_epi64x(static_cast<long long>(w[k]));
    __m256i best = none, second = none, best_index = _mm256_set1_epi64x(-1), index = _mm256_setr_epi64x(0, 1, 2, 3);
    for (int t = 0; t < train.padded; t += 4) {
      __m256i bytes = _mm256_setzero_si256();
      for (int k = 0; k < kWords; ++k) {
        const __m256i x = _mm256_xor_si256(qw[k], _mm256_loadu_si256(reinterpret_cast<const __m256i*>(train.word(k) + t)));
        const __m256i lo = _mm256_shuffle_epi8(table, _mm256_and_si256(x, low));
        const __m256i hi = _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(x, 4), low));
        bytes = _mm256_add_epi8(bytes, _mm256_add_epi8(lo, hi));
      }
      __m256i d = _mm256_sad_epu8(bytes, _mm256_setzero_si256());
      d = _mm256_blendv_epi8(d, none, _mm256_cmpgt_epi64(index, last));  // padding rows
      const __m256i below_best = _mm256_cmpgt_epi64(best, d), below_second = _mm256_cmpgt_epi64(second, d);
      second = _mm256_blendv_epi8(_mm256_blendv_epi8(second, d, below_second), best, below_best);
      best = _mm256_blendv_epi8(best, d, below_best);
      best_index = _mm256_blendv_epi8(best_index, index, below_best);
      index = _mm256_add_epi64(index, _mm256_set1_epi64x(4));
    }
    alignas(32) std::int64_t b[4], i[4], s[4];
    _mm256_store_si256(reinterpret_cast<__m256i*>(b), best);
    _mm256_store_si256(reinterpret_cast<__m256i*>(i), best_index);
    _mm256_store_si256(reinterpret_cast<__m256i*>(s), second);
    out[static_cast<size_t>(q)] = mergeLanes(b, i, s, 4);
  }
}

__attribute__((target("avx512f,avx512vpopcntdq"))) void avx512Kernel(const cv::Mat& query, const TransposedTrain& train,
                                                                   std::vector<TwoNearest>& out) {
  const __m512i none = _mm512_set1_epi64(257), last = _mm512_set1_epi64(train.rows - 1);
  for (int q = 0; q < query.rows; ++q) {
    std::uint64_t w[kWords];
    std::memcpy(w, query.ptr<std::uint8_t>(q), sizeof(w));
    __m512i qw[kWords];
    for (int k = 0; k < kWords; ++k) qw[k] = _mm512_set1_epi64(static_cast<long long>(w[k]));
    __m512i best = none, second = none, best_index = _mm512_set1_epi64(-1), index = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7);
    for (int t = 0; t < train.padded; t += 8) {
      __m512i d = _mm512_setzero_si512();
      for (int k = 0; k < kWords; ++k) {
        d = _mm512_add_epi64(d, _mm512_popcnt_epi64(_mm512_xor_si512(qw[k], _mm512_loadu_si512(train.word(k) + t))));
      }
      d = _mm512_mask_blend_epi64(_mm512_cmpgt_epi64_mask(index, last), d, none);  // padding rows
      const __mmask8 below_best = _mm512_cmplt_epi64_mask(d, best), below_second = _mm512_cmplt_epi64_mask(d, second);
      second = _mm512_mask_blend_epi64(below_best, _mm512_mask_blend_epi64(below_second, second, d), best);
      best = _mm512_mask_blend_epi64(below_best, best, d);
      best_index = _mm512_mask_blend_epi64(below_best, best_index, index);
      index = _mm512_add_epi64(index, _mm512_set1_epi64(8));
    }
    alignas(64) std::int64_t b[8], i[8], s[8];
    _mm512_store_si512(b, best);
    _mm512_store_si512(i, best_index);
    _mm512_store_si512(s, second);
    out[static_cast<size_t>(q)] = mergeLanes(b, i, s, 8);
  }
}

#endif

bool supported(HammingKernel kernel) {
  switch (kernel) {
    case HammingKernel::automatic:
    case HammingKernel::scalar: return true;
#ifdef GROUNDSLAM_X86
    case HammingKernel::avx2: return __builtin_cpu_supports("avx2");
    case HammingKernel::avx512: return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq");
#else
    case HammingKernel::avx2:
    case HammingKernel::avx512: return false;
#endif
  }
  return false;
}

}  // namespace

std::vector<HammingKernel> supportedHammingKernels() {
  std::vector<HammingKernel> kernels;
  for (HammingKernel k : {HammingKernel::scalar, HammingKernel::avx2, HammingKernel::avx512}) {
    if (supported(k)) kernels.push_back(k);
  }
  return kernels;
}

std::vector<TwoNearest> twoNearest(const cv::Mat& query, const cv::Mat& train, HammingKernel kernel) {
  for (const cv::Mat* m : {&query, &train}) {
    if (!m->empty() && (m->type() != CV_8UC1 || m->cols != 32)) throw std::invalid_argument("twoNearest: descriptors must be 32-byte CV_8U rows");
  }
  if (!supported(kernel)) throw std::invalid_argument("twoNearest: this CPU does not support the kernel asked for");
  static const HammingKernel fastest = supportedHammingKernels().back();
  if (kernel == HammingKernel::automatic) kernel = fastest;
  std::vector<TwoNearest> out(static_cast<size_t>(query.rows));
  if (query.empty() || train.empty()) return out;
#ifdef GROUNDSLAM_X86
  if (kernel == HammingKernel::avx512) {
    avx512Kernel(query, TransposedTrain(train), out);
    return out;
  }
  if (kernel == HammingKernel::avx2) {
    avx2Kernel(query, TransposedTrain(train), out);
    return out;
  }
#endif
  scalarKernel(query, train, out);
  return out;
}

}  // namespace groundslam
