#!/usr/bin/env bash
# A private CA and the certificates of a swarmpath farm, with openssl (EC P-256, 825 days).
#
#   deploy/tls/make-certs.sh DIR COORDINATOR_NAME_OR_IP [WORKER_NAME ...]
#
# DIR/ca.pem, ca.key                the CA (keep ca.key offline; it signs every certificate)
# DIR/coordinator.pem, .key         the coordinator's router: subjectAltName = the given name or
#                                   IP (workers check it), CN = coordinator
# DIR/<worker>.pem, <worker>.key    one client certificate per worker login, CN = <worker>: the
#                                   Zenoh access control matches it (cert_common_names)
# Running it again with new worker names adds their certificates with the same CA.
set -euo pipefail
dir=${1:?usage: make-certs.sh DIR COORDINATOR_NAME_OR_IP [WORKER ...]}
host=${2:?usage: make-certs.sh DIR COORDINATOR_NAME_OR_IP [WORKER ...]}
shift 2
mkdir -p "$dir" && cd "$dir"
umask 077
days=825
if [[ ! -f ca.pem ]]; then
  openssl req -x509 -new -nodes -newkey ec -pkeyopt ec_paramgen_curve:P-256 -keyout ca.key \
    -out ca.pem -days 3650 -subj "/CN=swarmpath CA" \
    -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign" \
    2>/dev/null
fi
issue() {  # issue NAME SUBJECT_ALT_NAME EXTENDED_KEY_USAGE
  local name=$1 san=$2 eku=$3
  openssl req -new -nodes -newkey ec -pkeyopt ec_paramgen_curve:P-256 -keyout "$name.key" \
    -out "$name.csr" -subj "/CN=$name" 2>/dev/null
  printf 'basicConstraints=CA:FALSE\nkeyUsage=critical,digitalSignature\nextendedKeyUsage=%s\nsubjectAltName=%s\n' \
    "$eku" "$san" > "$name.ext"
  openssl x509 -req -in "$name.csr" -CA ca.pem -CAkey ca.key -CAcreateserial -out "$name.pem" \
    -days "$days" -extfile "$name.ext" 2>/dev/null
  rm -f "$name.csr" "$name.ext"
}
if [[ $host =~ ^[0-9.]+$ || $host == *:* ]]; then san="IP:$host"; else san="DNS:$host"; fi
[[ -f coordinator.pem ]] || issue coordinator "$san" serverAuth
for worker in "$@"; do
  [[ $worker =~ ^[A-Za-z0-9][A-Za-z0-9_.-]*$ ]] || { echo "bad worker name: $worker" >&2; exit 2; }
  [[ -f $worker.pem ]] || issue "$worker" "DNS:$worker" clientAuth
done
chmod 0644 ca.pem ./*.pem
echo "certificates in $(pwd): $(ls ./*.pem | xargs -n1 basename | tr '\n' ' ')"
