// Internal: the words of an utterance as the HRI compares them (lower case, split at anything
// that is not a letter or digit), English stop words, edit distance for typo correction, and the
// check that an input is text at all.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace tripodal::hri {

/// Lower-case words of `text`: runs of ASCII letters and digits and of bytes beyond ASCII (kept
/// as they are); everything else separates.
[[nodiscard]] std::vector<std::string> words(std::string_view text);

/// Words that tell nothing about a topic ("the", "is", "what", "please", "robot's" clitics).
[[nodiscard]] bool is_stop_word(std::string_view word) noexcept;

/// Optimal-string-alignment distance (insertions, deletions, substitutions, transpositions of
/// neighbours), or `limit` + 1 as soon as it must exceed `limit`.
[[nodiscard]] std::size_t edit_distance(std::string_view a, std::string_view b, std::size_t limit);

/// Valid UTF-8 without control characters other than tab, line feed and carriage return, and
/// without U+FFFE and U+FFFF: text XML 1.0 can hold (find_xml_text_fault says where it is not).
[[nodiscard]] bool is_text(std::string_view bytes) noexcept;

[[nodiscard]] bool has_digit(std::string_view word) noexcept;

/// The word a chat abbreviation stands for ("u" -> "you", "thx" -> "thanks"), or `word` itself.
/// Typed visitors write them; neither the base nor a dictionary has them.
[[nodiscard]] std::string_view expand_chat_word(std::string_view word) noexcept;

/// Polite openings a visitor puts before a command ("could you", "please", "jinny") and closings
/// after it ("please"): the task templates are written without them, so the HRI strips them
/// before asking the planner (and typo correction must keep them).
[[nodiscard]] const std::vector<std::vector<std::string_view>>& polite_openings();
[[nodiscard]] const std::vector<std::string_view>& polite_closings();

/// Words that answer a yes-or-no question ("yes please", "sure", "go ahead"; "no", "cancel",
/// "don't"), for the HRI's confirmation and the recognizer's corpus.
[[nodiscard]] const std::vector<std::string_view>& yes_answers();
[[nodiscard]] const std::vector<std::string_view>& no_answers();
enum class Answer { yes, no, neither };
/// Yes when `ws` start with a yes answer's words, no with a no answer's, neither otherwise.
[[nodiscard]] Answer yes_or_no(const std::vector<std::string>& ws);

/// `ws` without polite openings (repeatedly: "jinny could you please ...") and closings; a
/// command's own words are never all stripped.
[[nodiscard]] std::vector<std::string> without_politeness(std::vector<std::string> ws);

}  // namespace tripodal::hri

namespace tripodal::hri {

/// The words of a request as the task grammar is written ("guide me to node 1"): without fillers
/// ("um", "well", "okay", "hey", the robot's name "jinny" first or last), polite openings ("could
/// you", "i'd like you to") and tails ("for me", "please", "now", "if you can"); "i want to go to"
/// as "go to", "show us node" and "i would like to see node" as "take me to node", "us" after a
/// guiding verb as "me", and the number after "node" ("node number one", "node twelve") as digits
/// (zero to twenty). Every rule is grammar: a word it does not know is left for the planner to
/// refuse, so a command parsed from the result accounts for every word of the request.
[[nodiscard]] std::vector<std::string> command_phrasing(std::vector<std::string> ws);

/// "zero".."twenty" as "0".."20"; other words unchanged.
[[nodiscard]] std::string number_word_as_digits(const std::string& word);

}  // namespace tripodal::hri
