// DDS Security for a fleet (tripodal::dds area; docs/distribution.md, "Security"): the OMG DDS
// Security plugins Cyclone DDS ships (authentication, access control, cryptography), as ROS 2's
// SROS2 uses them. A fleet's keys directory holds one CA, a certificate and key per identity
// (robot, operator tool, observer), the signed governance document (what is protected) and one
// signed permissions document per identity (what it may publish and subscribe). A participant
// given an identity's files joins only participants the same CA vouches for.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace tripodal::dds {

/// The files of one identity, as Cyclone DDS's security properties take them.
struct SecurityFiles {
  std::filesystem::path identity_ca;           ///< the CA that signed every identity certificate
  std::filesystem::path identity_certificate;  ///< this identity's certificate (PEM)
  std::filesystem::path private_key;           ///< its key (PEM)
  std::filesystem::path permissions_ca;        ///< the CA that signed governance and permissions
  std::filesystem::path governance;            ///< signed governance document (S/MIME)
  std::filesystem::path permissions;           ///< this identity's signed permissions (S/MIME)
  std::filesystem::path crl;                   ///< the CA's revocation list (PEM); empty: none
};

/// The files of `identity` in a keys directory made by make_fleet_keys. Throws DdsError naming
/// every file that is missing.
[[nodiscard]] SecurityFiles fleet_identity(const std::filesystem::path& keys_dir, std::string_view identity);

/// What an identity may do: robots and operator tools publish and subscribe every topic;
/// observers (a dashboard, a recorder) only subscribe.
enum class FleetRole { robot, operator_tool, observer };

struct FleetKeysOptions {
  std::filesystem::path out;  ///< created if missing; existing identities are refused, not overwritten
  std::vector<std::pair<std::string, FleetRole>> identities;
  std::uint32_t domain_id = 0;
  int valid_days = 365;
  std::string organisation = "tripodal fleet";
};

/// Makes a fleet's keys with Debian's openssl (the `openssl` program): an ECDSA P-256 CA (ca.pem,
/// ca_key.pem), per identity NAME a key and certificate (NAME_key.pem, NAME.pem, subject
/// "CN=NAME,O=organisation"), governance.p7s (discovery, liveliness and every topic's data
/// encrypted; unauthenticated participants refused) and NAME_permissions.p7s, signed by the CA.
/// Reuses ca.pem if the directory has one. Throws DdsError with openssl's message when a step
/// fails, std::invalid_argument for a name that is not a ROS 2 name or given twice.
void make_fleet_keys(const FleetKeysOptions& options);

/// Revokes `identity`'s certificate: adds it to the CA's revocation list, keys_dir/crl.pem (made
/// or renewed with `openssl ca -revoke` and `-gencrl`, the CA's database in keys_dir/ca_db/), which
/// fleet_identity() hands every participant from then on: Cyclone DDS's authentication refuses a
/// peer whose certificate the list names. Copy crl.pem to every robot. Throws DdsError naming the
/// file or openssl's message.
void revoke_fleet_identity(const std::filesystem::path& keys_dir, std::string_view identity);

/// Checks a signed governance or permissions document before Cyclone DDS reads it, so that a
/// malformed one is refused with its place: every problem as "FILE:LINE: error: WHAT" (not S/MIME,
/// XML not well formed, a missing or misplaced element, a date that does not parse, permissions
/// whose validity ended), all of them in one DdsError. Does not check the signature (Cyclone does).
void check_security_document(const std::filesystem::path& file, bool permissions);

/// Where Cyclone DDS's security plugins are (libdds_security_auth.so ...): $TRIPODAL_DDS_SECURITY_DIR,
/// or Debian's /usr/lib/<multiarch>/libddsc0debian. Throws DdsError when they are not there.
[[nodiscard]] std::filesystem::path security_plugin_dir();

}  // namespace tripodal::dds
