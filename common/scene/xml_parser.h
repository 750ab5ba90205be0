// A small XML reader for scene files: elements, attributes, comments, the <?xml ?> prolog, <!DOCTYPE>,
// CDATA and the five named entities plus numeric character references. Every element and attribute keeps
// the line it starts on so that errors can point at it. Text content is kept (trimmed) but scene files
// do not use it. Namespaces, DTD validation and processing instructions other than the prolog are not
// supported. Broken input throws SceneError("file:line: ...").
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace mlt {

struct XmlAttribute {
  std::string name, value;
  int line = 0;
};

struct XmlElement {
  std::string name;
  std::vector<XmlAttribute> attributes;  // in document order, names unique
  std::vector<XmlElement> children;
  std::string text;                      // concatenated character data, whitespace-trimmed
  std::string file;                      // the file this element was read from (for messages)
  int line = 0;

  const XmlAttribute* find(const std::string& attr) const;
  bool has(const std::string& attr) const { return find(attr) != nullptr; }
};

// Parses a complete document and returns its root element. `file` is used for messages only.
XmlElement parseXmlString(const std::string& text, const std::string& file);
// Reads and parses a file; an unreadable file is a SceneError naming it.
XmlElement parseXmlFile(const std::string& path);

}  // namespace mlt
