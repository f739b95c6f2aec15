#include "tripodal/hri/speech.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "text.hpp"
#include "tripodal/core/diagnostic.hpp"

namespace tripodal {

namespace {

void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFFU);
}
void put_u16(std::string& out, std::uint16_t v) {
  out += static_cast<char>(v & 0xFFU);
  out += static_cast<char>((v >> 8U) & 0xFFU);
}
std::uint32_t get_u32(std::string_view s, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8U) | static_cast<unsigned char>(s[at + static_cast<std::size_t>(i)]);
  return v;
}
std::uint16_t get_u16(std::string_view s, std::size_t at) {
  return static_cast<std::uint16_t>(static_cast<unsigned char>(s[at]) | (static_cast<unsigned char>(s[at + 1]) << 8U));
}

}  // namespace

std::string wav_bytes(const AudioClip& clip) {
  const auto data_bytes = static_cast<std::uint32_t>(clip.samples.size() * 2);
  std::string out;
  out.reserve(44 + data_bytes);
  out += "RIFF";
  put_u32(out, 36 + data_bytes);
  out += "WAVEfmt ";
  put_u32(out, 16);
  put_u16(out, 1);  // PCM
  put_u16(out, 1);  // mono
  put_u32(out, static_cast<std::uint32_t>(clip.sample_rate_hz));
  put_u32(out, static_cast<std::uint32_t>(clip.sample_rate_hz) * 2);
  put_u16(out, 2);
  put_u16(out, 16);
  out += "data";
  put_u32(out, data_bytes);
  for (const std::int16_t s : clip.samples) put_u16(out, static_cast<std::uint16_t>(s));
  return out;
}

void write_wav(const std::filesystem::path& file, const AudioClip& clip) {
  const std::string out = wav_bytes(clip);
  std::ofstream f(file, std::ios::binary);
  f.write(out.data(), static_cast<std::streamsize>(out.size()));
  if (!f) throw std::runtime_error(file.string() + ": cannot write the WAV file");
}

AudioClip read_wav(const std::filesystem::path& file) {
  const std::string bytes = read_config_file(file);
  const std::string name = file.string();
  const auto fail = [&](std::size_t at, const std::string& what) -> AudioClip {
    throw ConfigError(SourceLocation{name, 0, 0}, "at byte " + std::to_string(at) + ": " + what);
  };
  const std::string_view s = bytes;
  if (s.size() < 12 || s.substr(0, 4) != "RIFF" || s.substr(8, 4) != "WAVE") return fail(0, "not a RIFF WAVE file");
  std::size_t at = 12;
  int channels = 0;
  AudioClip clip;
  bool have_format = false;
  while (at + 8 <= s.size()) {
    const std::string_view id = s.substr(at, 4);
    const std::uint32_t size = get_u32(s, at + 4);
    const std::size_t body = at + 8;
    if (size > s.size() - body) return fail(at, "chunk '" + std::string(id) + "' of " + std::to_string(size) + " bytes runs past the end of the file");
    if (id == "fmt ") {
      if (size < 16) return fail(at, "format chunk of " + std::to_string(size) + " bytes; expected 16 or more");
      if (get_u16(s, body) != 1) return fail(body, "format " + std::to_string(get_u16(s, body)) + "; expected 1 (PCM)");
      channels = get_u16(s, body + 2);
      clip.sample_rate_hz = static_cast<int>(get_u32(s, body + 4));
      if (get_u16(s, body + 14) != 16) return fail(body + 14, std::to_string(get_u16(s, body + 14)) + " bits per sample; expected 16");
      if (channels < 1) return fail(body + 2, "no channels");
      if (clip.sample_rate_hz < 1000 || clip.sample_rate_hz > 192000) return fail(body + 4, "sample rate " + std::to_string(clip.sample_rate_hz) + " Hz; expected 1000 to 192000");
      have_format = true;
    } else if (id == "data") {
      if (!have_format) return fail(at, "data before the format chunk");
      const std::size_t frame = static_cast<std::size_t>(channels) * 2;
      const std::size_t frames = size / frame;
      clip.samples.resize(frames);
      for (std::size_t i = 0; i < frames; ++i) clip.samples[i] = static_cast<std::int16_t>(get_u16(s, body + i * frame));
      return clip;
    }
    at = body + size + (size & 1U);  // chunks are padded to an even size
  }
  return fail(at, "no data chunk");
}

AudioClip resample(const AudioClip& clip, int rate_hz) {
  if (rate_hz <= 0) throw std::invalid_argument("resample: rate " + std::to_string(rate_hz) + " Hz; expected > 0");
  if (clip.sample_rate_hz == rate_hz || clip.samples.empty()) {
    AudioClip same = clip;
    same.sample_rate_hz = rate_hz;
    return same;
  }
  const double ratio = static_cast<double>(clip.sample_rate_hz) / rate_hz;  // input samples per output sample
  const double cutoff = std::min(1.0, 1.0 / ratio) * 0.95;  // of the input's Nyquist frequency
  constexpr int kHalfTaps = 16;
  const double half_width = kHalfTaps / cutoff;
  AudioClip out;
  out.sample_rate_hz = rate_hz;
  const auto n_out = static_cast<std::size_t>(std::floor(static_cast<double>(clip.samples.size()) / ratio));
  out.samples.resize(n_out);
  const auto n_in = static_cast<std::ptrdiff_t>(clip.samples.size());
  for (std::size_t i = 0; i < n_out; ++i) {
    const double t = static_cast<double>(i) * ratio;
    const auto first = static_cast<std::ptrdiff_t>(std::ceil(t - half_width));
    const auto last = static_cast<std::ptrdiff_t>(std::floor(t + half_width));
    double acc = 0.0;
    for (std::ptrdiff_t k = std::max<std::ptrdiff_t>(first, 0); k <= std::min(last, n_in - 1); ++k) {
      const double x = static_cast<double>(k) - t;
      const double arg = std::numbers::pi * x * cutoff;
      const double sinc = std::abs(arg) < 1e-9 ? 1.0 : std::sin(arg) / arg;
      // Hann window over the kernel's width.
      const double window = 0.5 * (1.0 + std::cos(std::numbers::pi * x / half_width));
      acc += clip.samples[static_cast<std::size_t>(k)] * sinc * window * cutoff;
    }
    out.samples[i] = static_cast<std::int16_t>(std::clamp(std::lround(acc), -32768L, 32767L));
  }
  return out;
}

WordErrors word_errors(std::string_view reference, std::string_view hypothesis) {
  const std::vector<std::string> r = hri::words(reference);
  const std::vector<std::string> h = hri::words(hypothesis);
  std::vector<std::size_t> prev(h.size() + 1), cur(h.size() + 1);
  for (std::size_t j = 0; j <= h.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= r.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= h.size(); ++j) {
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (r[i - 1] == h[j - 1] ? 0 : 1)});
    }
    std::swap(prev, cur);
  }
  return {prev[h.size()], r.size()};
}

double word_error_rate(std::string_view reference, std::string_view hypothesis) {
  const WordErrors e = word_errors(reference, hypothesis);
  if (e.reference_words == 0) return e.errors == 0 ? 0.0 : 1.0;
  return static_cast<double>(e.errors) / static_cast<double>(e.reference_words);
}

namespace {

constexpr std::array<std::string_view, 20> kSmall = {"zero",    "one",     "two",       "three",    "four",
                                                     "five",    "six",     "seven",     "eight",    "nine",
                                                     "ten",     "eleven",  "twelve",    "thirteen", "fourteen",
                                                     "fifteen", "sixteen", "seventeen", "eighteen", "nineteen"};
constexpr std::array<std::string_view, 10> kTens = {"", "", "twenty", "thirty", "forty", "fifty", "sixty", "seventy", "eighty", "ninety"};

std::string number_words(unsigned n) {
  if (n < 20) return std::string(kSmall[n]);
  if (n < 100) return std::string(kTens[n / 10]) + (n % 10 != 0 ? " " + std::string(kSmall[n % 10]) : "");
  return std::string(kSmall[n / 100]) + " hundred" + (n % 100 != 0 ? " " + number_words(n % 100) : "");
}

// Words for speaking: letters, digits and apostrophes inside words ("how's" is one word of the
// recognizer's dictionary); a hyphen before a digit joins.
std::vector<std::string> spoken_tokens(std::string_view text) {
  std::vector<std::string> out;
  std::string word;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const auto u = static_cast<unsigned char>(c);
    const bool alnum = (u >= 'a' && u <= 'z') || (u >= '0' && u <= '9');
    if (alnum) {
      word += c;
    } else if (u >= 'A' && u <= 'Z') {
      word += static_cast<char>(u - 'A' + 'a');
    } else if ((c == '\'' && !word.empty() && i + 1 < text.size() && std::isalpha(static_cast<unsigned char>(text[i + 1])) != 0) ||
               (c == '-' && !word.empty() && i + 1 < text.size() && text[i + 1] >= '0' && text[i + 1] <= '9')) {
      if (c == '\'') word += c;
    } else if (!word.empty()) {
      out.push_back(std::move(word));
      word.clear();
    }
  }
  if (!word.empty()) out.push_back(std::move(word));
  return out;
}

}  // namespace

std::string spoken_form(std::string_view text) {
  std::string out;
  const auto add = [&](const std::string& w) { out += (out.empty() ? "" : " ") + w; };
  for (const std::string& w : spoken_tokens(text)) {
    const std::size_t digit = w.find_first_of("0123456789");
    if (digit == std::string::npos) {
      add(w);
      continue;
    }
    // Letters before the number are spelled ("psr1" -> "p s r one").
    for (std::size_t i = 0; i < digit; ++i) {
      if (w[i] != '\'') add(std::string(1, w[i]));
    }
    const std::string digits = w.substr(digit);
    if (digits.size() <= 3 && std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      add(number_words(static_cast<unsigned>(std::stoul(digits))));
    } else {
      for (const char c : digits) {
        if (c >= '0' && c <= '9') {
          add(std::string(kSmall[static_cast<std::size_t>(c - '0')]));
        } else {
          add(std::string(1, c));
        }
      }
    }
  }
  return out;
}

std::string typed_form(std::string_view words) {
  std::vector<std::string> in;
  std::istringstream s{std::string(words)};
  for (std::string w; s >> w;) in.push_back(w);
  const auto small = [](const std::string& w) -> int {
    for (std::size_t i = 0; i < kSmall.size(); ++i) {
      if (kSmall[i] == w) return static_cast<int>(i);
    }
    return -1;
  };
  const auto tens = [](const std::string& w) -> int {
    for (std::size_t i = 2; i < kTens.size(); ++i) {
      if (kTens[i] == w) return static_cast<int>(i) * 10;
    }
    return -1;
  };
  // Number words to digits first ("twenty one" -> "21").
  std::vector<std::string> mid;
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (const int t = tens(in[i]); t >= 0) {
      int n = t;
      if (i + 1 < in.size() && small(in[i + 1]) > 0 && small(in[i + 1]) < 10) n += small(in[++i]);
      mid.push_back(std::to_string(n));
    } else if (const int n = small(in[i]); n >= 0) {
      mid.push_back(std::to_string(n));
    } else {
      mid.push_back(in[i]);
    }
  }
  // Spelled letters right before a number join it: "p s r 2" -> "psr2".
  std::vector<std::string> out;
  for (std::size_t i = 0; i < mid.size();) {
    std::size_t j = i;
    while (j < mid.size() && mid[j].size() == 1 && mid[j][0] >= 'a' && mid[j][0] <= 'z') ++j;
    if (j - i >= 2 && j < mid.size() && hri::has_digit(mid[j])) {
      std::string joined;
      for (std::size_t k = i; k <= j; ++k) joined += mid[k];
      out.push_back(joined);
      i = j + 1;
    } else {
      out.push_back(mid[i]);
      ++i;
    }
  }
  std::string text;
  for (const auto& w : out) text += (text.empty() ? "" : " ") + w;
  return text;
}

std::string arpa_bigram_model(const std::vector<std::string>& sentences, const std::function<bool(std::string_view)>& known) {
  constexpr double kDiscount = 0.5;
  std::map<std::string, double> unigram;
  std::map<std::string, std::map<std::string, double>> bigram;
  for (const auto& sentence : sentences) {
    std::vector<std::string> ws{"<s>"};
    std::istringstream s(spoken_form(sentence));
    for (std::string w; s >> w;) {
      if (!known || known(w)) ws.push_back(w);
    }
    ws.emplace_back("</s>");
    if (ws.size() == 2) continue;
    for (std::size_t i = 0; i < ws.size(); ++i) {
      unigram[ws[i]] += 1.0;
      if (i + 1 < ws.size()) bigram[ws[i]][ws[i + 1]] += 1.0;
    }
  }
  double total = 0.0;
  for (const auto& [w, c] : unigram) {
    if (w != "<s>") total += c;
  }
  // Unigrams add one to every count so that no word is impossible after an unseen history.
  // (Kneser-Ney continuation counts instead lowered the word error rate but let out-of-domain
  // sentences through the confidence threshold more often: docs/hri.md, "Voice".)
  const double vocab = static_cast<double>(unigram.size());
  std::map<std::string, double> p1;
  for (const auto& [w, c] : unigram) p1[w] = (c + 1.0) / (total + vocab);
  std::ostringstream out;
  std::size_t n2 = 0;
  for (const auto& [h, next] : bigram) n2 += next.size();
  out << "\\data\\\nngram 1=" << unigram.size() << "\nngram 2=" << n2 << "\n\n\\1-grams:\n";
  out.setf(std::ios::fixed);
  out.precision(6);
  for (const auto& [w, c] : unigram) {
    const double logp = w == "<s>" ? -99.0 : std::log10(p1[w]);
    const auto it = bigram.find(w);
    if (it == bigram.end()) {
      out << logp << ' ' << w << '\n';
      continue;
    }
    // Absolute discounting: kDiscount of every seen bigram's count goes to the unigrams of the
    // words not seen after w, normalised over them.
    const double seen_mass_uni = [&] {
      double m = 0.0;
      for (const auto& [v, _] : it->second) m += p1[v];
      return m;
    }();
    const double left = kDiscount * static_cast<double>(it->second.size()) / unigram[w];
    const double backoff = seen_mass_uni < 1.0 ? left / (1.0 - seen_mass_uni) : 1e-6;
    out << logp << ' ' << w << ' ' << std::log10(std::max(backoff, 1e-12)) << '\n';
  }
  out << "\n\\2-grams:\n";
  for (const auto& [h, next] : bigram) {
    for (const auto& [w, c] : next) {
      out << std::log10((c - kDiscount) / unigram[h]) << ' ' << h << ' ' << w << '\n';
    }
  }
  out << "\n\\end\\\n";
  return out.str();
}

namespace {

// Every sentence of a command form: "[the]" in and out, "{node}" each value.
void expand_form(const std::vector<std::string>& tokens, std::size_t at, std::string sentence,
                 const std::map<std::string, std::vector<std::string>>& slot_values, std::vector<std::string>& out) {
  if (at == tokens.size()) {
    out.push_back(sentence);
    return;
  }
  const std::string& t = tokens[at];
  const auto with = [&](const std::string& w) { return sentence.empty() ? w : sentence + " " + w; };
  if (t.size() > 2 && t.front() == '[' && t.back() == ']') {
    expand_form(tokens, at + 1, sentence, slot_values, out);
    expand_form(tokens, at + 1, with(t.substr(1, t.size() - 2)), slot_values, out);
  } else if (t.size() > 2 && t.front() == '{' && t.back() == '}') {
    std::string name = t.substr(1, t.size() - 2);
    if (name.size() > 3 && name.compare(name.size() - 3, 3, "...") == 0) name.resize(name.size() - 3);
    const auto values = slot_values.find(name);
    if (values == slot_values.end()) return;
    for (const auto& v : values->second) expand_form(tokens, at + 1, with(v), slot_values, out);
  } else {
    expand_form(tokens, at + 1, with(t), slot_values, out);
  }
}

}  // namespace

std::vector<std::string> speech_corpus(const KnowledgeBase& base, const std::vector<std::string>& command_forms,
                                       const std::map<std::string, std::vector<std::string>>& slot_values) {
  std::vector<std::string> out;
  for (const auto& e : base.entries()) {
    out.insert(out.end(), e.questions.begin(), e.questions.end());
    out.insert(out.end(), e.keywords.begin(), e.keywords.end());
    if (!e.action.empty()) out.push_back(e.action);
    // Not the answers' sentences: they won 2 of 68 development utterances but spread the model
    // over the robot's own words, and the exhibit hall visit's "Thank you" was heard "that two".
  }
  for (const auto& form : command_forms) {
    std::vector<std::string> tokens;
    std::istringstream s(form);
    for (std::string t; s >> t;) tokens.push_back(t);
    const std::size_t first = out.size();
    expand_form(tokens, 0, {}, slot_values, out);
    if (out.size() == first) continue;
    // Polite requests, once per form: enough for the bigrams ("<s> please", "please guide",
    // "one please", "could you guide") without outweighing the questions. The HRI strips more
    // politeness ("can you", "i want you to"), but in the model those put a question's words
    // before every command's verb, and the spoken round trip lost more than it gained
    // (docs/hri.md, "Voice").
    for (const char* opening : {"please", "could you", "would you"}) out.push_back(std::string(opening) + " " + out[first]);
    out.push_back(out[first] + " please");
  }
  // The answers to the HRI's "Did you ask me to ...? Please say yes or no."
  for (const auto& answers : {hri::yes_answers(), hri::no_answers()}) {
    out.insert(out.end(), answers.begin(), answers.end());
  }
  out.emplace_back("yes please");
  out.emplace_back("no thanks");
  return out;
}

std::vector<std::string> pocketsphinx_dictionary_words(const std::filesystem::path& model_dir) {
  std::ifstream in(model_dir / "cmudict-en-us.dict");
  if (!in) throw std::runtime_error((model_dir / "cmudict-en-us.dict").string() + ": cannot read the dictionary");
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) {
    std::string w = line.substr(0, line.find(' '));
    if (const auto paren = w.find('('); paren != std::string::npos) continue;  // alternative pronunciations
    if (!w.empty()) out.push_back(std::move(w));
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::optional<std::string> arpabet_from_espeak(std::string_view mnemonics) {
  // espeak-ng's English mnemonics (its own phoneme documentation, US variant), longest first where
  // one is the start of another ("aI@" before "aI", "tS" before "t").
  struct Phone {
    std::string_view espeak;
    std::string_view arpabet;
  };
  static constexpr std::array<Phone, 59> kPhones = {{
      {"aI@", "AY ER"}, {"aI3", "AY ER"}, {"aU@", "AW ER"}, {"aU3", "AW ER"}, {"i@3", "IY R"}, {"A@", "AA R"},  {"e@", "EH R"},
      {"i@", "IY R"},   {"U@", "UH R"},   {"o@", "AO R"},   {"O@", "AO R"},   {"3:", "ER"},    {"@L", "AH L"},  {"@2", "AH"},
      {"@5", "AH"},     {"I#", "IH"},     {"I2", "IH"},     {"i:", "IY"},     {"u:", "UW"},    {"A:", "AA"},    {"O:", "AO"},
      {"eI", "EY"},     {"aI", "AY"},     {"aU", "AW"},     {"oU", "OW"},     {"OI", "OY"},    {"tS", "CH"},    {"dZ", "JH"},
      {"t#", "T"},      {"n-", "N"},      {"l-", "L"},      {"r-", "R"},      {"a#", "AH"},    {"a", "AE"},     {"@", "AH"},
      {"3", "ER"},      {"E", "EH"},      {"i", "IY"},      {"I", "IH"},      {"0", "AA"},     {"O", "AO"},     {"U", "UH"},
      {"V", "AH"},      {"u", "UW"},      {"e", "EH"},      {"o", "OW"},      {"A", "AA"},     {"T", "TH"},     {"D", "DH"},
      {"S", "SH"},      {"Z", "ZH"},      {"N", "NG"},      {"j", "Y"},       {"h", "HH"},     {"x", "K"},      {"?", "T"},
      {"C", "HH"},      {"w", "W"},       {"r", "R"},
  }};
  static constexpr std::string_view kPlain = "pbtdkgfvszmnl";  // the same letter, upper case
  std::string out;
  const auto add = [&](std::string_view phones) {
    if (!out.empty()) out += ' ';
    out += phones;
  };
  std::size_t i = 0;
  while (i < mnemonics.size()) {
    const char c = mnemonics[i];
    if (c == '\'' || c == ',' || c == '_' || c == '|' || c == '%' || c == '=' || c == ' ' || c == ':') {
      ++i;  // stress, syllable and word marks; a lone length mark
      continue;
    }
    const auto phone = std::find_if(kPhones.begin(), kPhones.end(), [&](const Phone& p) { return mnemonics.substr(i).starts_with(p.espeak); });
    if (phone != kPhones.end()) {
      add(phone->arpabet);
      i += phone->espeak.size();
    } else if (kPlain.find(c) != std::string_view::npos) {
      add(std::string(1, static_cast<char>(std::toupper(static_cast<unsigned char>(c)))));
      ++i;
    } else {
      return std::nullopt;
    }
  }
  if (out.empty()) return std::nullopt;
  return out;
}

PocketsphinxOptions recognizer_options(const std::vector<std::string>& corpus, PocketsphinxOptions base) {
  const std::vector<std::string> dict = pocketsphinx_dictionary_words(base.model_dir);
  const auto in_dictionary = [&](std::string_view w) { return std::binary_search(dict.begin(), dict.end(), w); };
  for (const auto& sentence : corpus) {
    std::istringstream s(spoken_form(sentence));
    for (std::string w; s >> w;) {
      if (in_dictionary(w) || base.extra_pronunciations.count(w) != 0) continue;
      if (auto phones = espeak_pronunciation(w)) base.extra_pronunciations.emplace(w, std::move(*phones));
    }
  }
  base.language_model = arpa_bigram_model(corpus, [&](std::string_view w) {
    return in_dictionary(w) || base.extra_pronunciations.count(std::string(w)) != 0;
  });
  return base;
}

}  // namespace tripodal
