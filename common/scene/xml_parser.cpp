#include "common/scene/xml_parser.h"

#include <cstdint>
#include <fstream>
#include <sstream>

#include "common/scene/scene_error.h"

namespace mlt {

const XmlAttribute* XmlElement::find(const std::string& attr) const {
  for (const auto& a : attributes)
    if (a.name == attr) return &a;
  return nullptr;
}

namespace {

bool isNameStart(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == ':' || (unsigned char)c >= 0x80;
}
bool isNameChar(char c) { return isNameStart(c) || (c >= '0' && c <= '9') || c == '-' || c == '.'; }
bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

std::string trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && isSpace(s[a])) ++a;
  while (b > a && isSpace(s[b - 1])) --b;
  return s.substr(a, b - a);
}

void appendUtf8(std::string& out, uint32_t cp) {
  if (cp < 0x80) {
    out += char(cp);
  } else if (cp < 0x800) {
    out += char(0xC0 | (cp >> 6));
    out += char(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += char(0xE0 | (cp >> 12));
    out += char(0x80 | ((cp >> 6) & 0x3F));
    out += char(0x80 | (cp & 0x3F));
  } else {
    out += char(0xF0 | (cp >> 18));
    out += char(0x80 | ((cp >> 12) & 0x3F));
    out += char(0x80 | ((cp >> 6) & 0x3F));
    out += char(0x80 | (cp & 0x3F));
  }
}

class Parser {
 public:
  Parser(const std::string& text, const std::string& file) : s_(text), file_(file) {}

  XmlElement parseDocument() {
    if (s_.size() >= 3 && (unsigned char)s_[0] == 0xEF && (unsigned char)s_[1] == 0xBB && (unsigned char)s_[2] == 0xBF)
      pos_ = 3;  // UTF-8 byte-order mark
    skipMisc(true);
    if (pos_ >= s_.size()) fail("the document has no root element");
    if (s_[pos_] != '<') fail("expected '<' to start the root element");
    XmlElement root = parseElement();
    skipMisc(false);
    if (pos_ < s_.size()) fail("unexpected content after the root element </" + root.name + ">");
    return root;
  }

 private:
  [[noreturn]] void fail(const std::string& msg) const { throw SceneError(file_, line_, "XML error: " + msg); }
  [[noreturn]] void failAt(int line, const std::string& msg) const {
    throw SceneError(file_, line, "XML error: " + msg);
  }

  bool startsWith(const char* lit) const { return s_.compare(pos_, std::char_traits<char>::length(lit), lit) == 0; }
  void advance(size_t n = 1) {
    for (size_t i = 0; i < n && pos_ < s_.size(); ++i, ++pos_)
      if (s_[pos_] == '\n') ++line_;
  }
  void skipSpace() {
    while (pos_ < s_.size() && isSpace(s_[pos_])) advance();
  }
  // Skips up to and including `end`; fails naming `what` and the line it started on if never found.
  void skipPast(const char* end, const char* what) {
    const int startLine = line_;
    const size_t at = s_.find(end, pos_);
    if (at == std::string::npos) failAt(startLine, std::string("unterminated ") + what);
    advance(at + std::char_traits<char>::length(end) - pos_);
  }

  // Whitespace, comments, <?...?> and <!DOCTYPE ...> between top-level constructs.
  void skipMisc(bool prologAllowed) {
    for (;;) {
      skipSpace();
      if (startsWith("<!--")) {
        parseComment();
      } else if (startsWith("<?")) {
        if (!prologAllowed && startsWith("<?xml")) fail("<?xml ?> declaration is only allowed at the start");
        skipPast("?>", "processing instruction '<?'");
      } else if (startsWith("<!DOCTYPE")) {
        skipDoctype();
      } else {
        return;
      }
    }
  }
  void parseComment() {
    const int startLine = line_;
    advance(4);
    const size_t at = s_.find("--", pos_);
    if (at == std::string::npos) failAt(startLine, "unterminated comment '<!--'");
    advance(at - pos_);
    if (!startsWith("-->")) fail("'--' is not allowed inside a comment");
    advance(3);
  }
  void skipDoctype() {
    const int startLine = line_;
    int depth = 0;
    while (pos_ < s_.size()) {
      const char c = s_[pos_];
      if (c == '[') ++depth;
      if (c == ']') --depth;
      if (c == '>' && depth <= 0) {
        advance();
        return;
      }
      advance();
    }
    failAt(startLine, "unterminated <!DOCTYPE");
  }

  std::string parseName(const char* what) {
    if (pos_ >= s_.size() || !isNameStart(s_[pos_])) fail(std::string("expected ") + what);
    const size_t start = pos_;
    while (pos_ < s_.size() && isNameChar(s_[pos_])) advance();
    return s_.substr(start, pos_ - start);
  }

  // Decodes entity and character references in raw text.
  std::string decode(const std::string& raw, int line) const {
    std::string out;
    out.reserve(raw.size());
    for (size_t i = 0; i < raw.size(); ++i) {
      const char c = raw[i];
      if (c == '\n') ++line;
      if (c != '&') {
        out += c;
        continue;
      }
      const size_t semi = raw.find(';', i);
      if (semi == std::string::npos || semi - i > 12) failAt(line, "'&' does not start an entity (write &amp;)");
      const std::string ent = raw.substr(i + 1, semi - i - 1);
      if (ent == "lt") out += '<';
      else if (ent == "gt") out += '>';
      else if (ent == "amp") out += '&';
      else if (ent == "quot") out += '"';
      else if (ent == "apos") out += '\'';
      else if (ent.size() > 1 && ent[0] == '#') {
        const bool hex = ent[1] == 'x' || ent[1] == 'X';
        const std::string digits = ent.substr(hex ? 2 : 1);
        if (digits.empty()) failAt(line, "empty character reference &" + ent + ";");
        uint32_t cp = 0;
        for (char d : digits) {
          int v;
          if (d >= '0' && d <= '9') v = d - '0';
          else if (hex && d >= 'a' && d <= 'f') v = d - 'a' + 10;
          else if (hex && d >= 'A' && d <= 'F') v = d - 'A' + 10;
          else failAt(line, "bad character reference &" + ent + ";");
          cp = cp * (hex ? 16 : 10) + v;
          if (cp > 0x10FFFF) failAt(line, "character reference &" + ent + "; is out of range");
        }
        if (cp == 0) failAt(line, "character reference &#0; is not allowed");
        appendUtf8(out, cp);
      } else {
        failAt(line, "unknown entity &" + ent + ";");
      }
      i = semi;
    }
    return out;
  }

  XmlElement parseElement() {
    if (++depth_ > kMaxDepth) fail("elements nested more than " + std::to_string(kMaxDepth) + " deep");
    XmlElement el;
    el.file = file_;
    el.line = line_;
    advance();  // '<'
    el.name = parseName("an element name after '<'");
    // Attributes.
    for (;;) {
      const bool hadSpace = pos_ < s_.size() && isSpace(s_[pos_]);
      skipSpace();
      if (pos_ >= s_.size()) failAt(el.line, "unterminated start tag <" + el.name);
      if (startsWith("/>")) {
        advance(2);
        --depth_;
        return el;
      }
      if (s_[pos_] == '>') {
        advance();
        break;
      }
      if (!hadSpace) fail("expected whitespace, '>' or '/>' in <" + el.name + ">");
      XmlAttribute a;
      a.line = line_;
      a.name = parseName(("an attribute name in <" + el.name + ">").c_str());
      skipSpace();
      if (pos_ >= s_.size() || s_[pos_] != '=') fail("expected '=' after attribute '" + a.name + "'");
      advance();
      skipSpace();
      if (pos_ >= s_.size() || (s_[pos_] != '"' && s_[pos_] != '\'')) fail("attribute '" + a.name + "' needs a quoted value");
      const char q = s_[pos_];
      advance();
      const int valueLine = line_;
      const size_t end = s_.find(q, pos_);
      if (end == std::string::npos) failAt(valueLine, "unterminated value of attribute '" + a.name + "'");
      const std::string raw = s_.substr(pos_, end - pos_);
      if (raw.find('<') != std::string::npos) fail("'<' is not allowed in the value of attribute '" + a.name + "'");
      a.value = decode(raw, valueLine);
      advance(end + 1 - pos_);
      if (el.find(a.name)) failAt(a.line, "duplicate attribute '" + a.name + "' in <" + el.name + ">");
      el.attributes.push_back(std::move(a));
    }
    // Content.
    std::string text;
    for (;;) {
      if (pos_ >= s_.size()) failAt(el.line, "element <" + el.name + "> is never closed");
      if (startsWith("</")) {
        advance(2);
        const int closeLine = line_;
        const std::string name = parseName("an element name after '</'");
        if (name != el.name)
          failAt(closeLine, "closing tag </" + name + "> does not match <" + el.name + "> opened on line " +
                                std::to_string(el.line));
        skipSpace();
        if (pos_ >= s_.size() || s_[pos_] != '>') fail("expected '>' to end </" + name);
        advance();
        break;
      }
      if (startsWith("<!--")) {
        parseComment();
      } else if (startsWith("<![CDATA[")) {
        advance(9);
        const int startLine = line_;
        const size_t at = s_.find("]]>", pos_);
        if (at == std::string::npos) failAt(startLine, "unterminated CDATA section");
        text += s_.substr(pos_, at - pos_);
        advance(at + 3 - pos_);
      } else if (startsWith("<?")) {
        if (startsWith("<?xml")) fail("<?xml ?> declaration is only allowed at the start");
        skipPast("?>", "processing instruction '<?'");
      } else if (s_[pos_] == '<') {
        el.children.push_back(parseElement());
      } else {
        const int startLine = line_;
        const size_t at = s_.find('<', pos_);
        const size_t end = at == std::string::npos ? s_.size() : at;
        const std::string raw = s_.substr(pos_, end - pos_);
        if (raw.find('>') != std::string::npos && raw.find("]]>") != std::string::npos)
          fail("']]>' is not allowed in text");
        text += decode(raw, startLine);
        advance(end - pos_);
      }
    }
    el.text = trim(text);
    --depth_;
    return el;
  }

  const std::string& s_;
  std::string file_;
  size_t pos_ = 0;
  int line_ = 1;
  int depth_ = 0;
  static constexpr int kMaxDepth = 256;
};

}  // namespace

XmlElement parseXmlString(const std::string& text, const std::string& file) {
  Parser p(text, file);
  return p.parseDocument();
}

XmlElement parseXmlFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path, 0, "cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw SceneError(path, 0, "error while reading file");
  return parseXmlString(ss.str(), path);
}

}  // namespace mlt
