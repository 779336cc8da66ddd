/* A Cyclone DDS participant for the DDS Security interoperability tests (see cyclone_c_peer.py,
 * which generates tyre_msgs.h/.c with idlc and printers.h, and compiles this file).
 *
 *   cyclone_peer read <enclave_dir|-> <count> <timeout_s>
 *   cyclone_peer command <enclave_dir|-> <count> <operator_name>
 *   cyclone_peer sample <enclave_dir|-> <count> <timeout_s>   (RigSample seq 0.. at 50 Hz once matched)
 *
 * With an enclave directory (an SROS2 enclave: identity_ca.cert.pem, cert.pem, key.pem,
 * permissions_ca.cert.pem, governance.p7s, permissions.p7s) the participant uses Cyclone's
 * builtin DDS Security plugins; with "-" it is a plain participant. Domain: ROS_DOMAIN_ID. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dds/dds.h"
#include "tyre_msgs.h"

static void print_json_string(const char *s) {
  putchar('"');
  for (; s && *s; s++) {
    unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\') printf("\\%c", c);
    else if (c < 0x20) printf("\\u%04x", c);
    else putchar(c);
  }
  putchar('"');
}

#include "printers.h"

static void set_file_prop(dds_qos_t *qos, const char *name, const char *dir, const char *file) {
  char value[4096];
  snprintf(value, sizeof value, "file:%s/%s", dir, file);
  dds_qset_prop(qos, name, value);
}

/* The builtin plugins (authentication PKI-DH, access control Permissions, crypto AES-GCM-GMAC)
 * and the six files of an enclave, as participant QoS properties (DDS Security 1.1 names). */
static dds_qos_t *secure_qos(const char *enclave) {
  dds_qos_t *qos = dds_create_qos();
  static const char *libs[][4] = {
      {"auth", "libdds_security_auth.so", "init_authentication", "finalize_authentication"},
      {"access", "libdds_security_ac.so", "init_access_control", "finalize_access_control"},
      {"crypto", "libdds_security_crypto.so", "init_crypto", "finalize_crypto"},
  };
  for (size_t i = 0; i < 3; i++) {
    char name[128], path[512];
    snprintf(path, sizeof path, "%s/%s", PLUGIN_DIR, libs[i][1]);
    snprintf(name, sizeof name, "dds.sec.%s.library.path", libs[i][0]);
    dds_qset_prop(qos, name, path);
    snprintf(name, sizeof name, "dds.sec.%s.library.init", libs[i][0]);
    dds_qset_prop(qos, name, libs[i][2]);
    snprintf(name, sizeof name, "dds.sec.%s.library.finalize", libs[i][0]);
    dds_qset_prop(qos, name, libs[i][3]);
  }
  set_file_prop(qos, "dds.sec.auth.identity_ca", enclave, "identity_ca.cert.pem");
  set_file_prop(qos, "dds.sec.auth.identity_certificate", enclave, "cert.pem");
  set_file_prop(qos, "dds.sec.auth.private_key", enclave, "key.pem");
  set_file_prop(qos, "dds.sec.access.permissions_ca", enclave, "permissions_ca.cert.pem");
  set_file_prop(qos, "dds.sec.access.governance", enclave, "governance.p7s");
  set_file_prop(qos, "dds.sec.access.permissions", enclave, "permissions.p7s");
  return qos;
}

static dds_qos_t *reliable_qos(void) {
  dds_qos_t *qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  return qos;
}

int main(int argc, char **argv) {
  if (argc != 5 || (strcmp(argv[1], "read") != 0 && strcmp(argv[1], "command") != 0 &&
                    strcmp(argv[1], "sample") != 0)) {
    fprintf(stderr, "usage: %s read|command|sample <enclave_dir|-> <count> <timeout_s|operator>\n", argv[0]);
    return 1;
  }
  const char *env = getenv("ROS_DOMAIN_ID");
  dds_domainid_t domain = env ? (dds_domainid_t)atoi(env) : 0;
  dds_qos_t *pqos = strcmp(argv[2], "-") == 0 ? NULL : secure_qos(argv[2]);
  dds_entity_t participant = dds_create_participant(domain, pqos, NULL);
  if (pqos) dds_delete_qos(pqos);
  if (participant < 0) {
    printf("PARTICIPANT_REFUSED %s\n", dds_strretcode(participant));
    return 4;
  }
  long count = atol(argv[3]);
  dds_qos_t *qos = reliable_qos();
  int rc = 0;
  if (strcmp(argv[1], "read") == 0) {
    double timeout_s = atof(argv[4]);
    dds_entity_t topic = dds_create_topic(participant, &tyre_msgs_msg_dds__RigSample__desc, "rt/rig/sample", NULL, NULL);
    dds_entity_t reader = topic < 0 ? topic : dds_create_reader(participant, topic, qos, NULL);
    if (reader < 0) {
      printf("READER_REFUSED %s\n", dds_strretcode(reader));
      return 3;
    }
    long got = 0;
    dds_time_t deadline = dds_time() + (dds_duration_t)(timeout_s * 1e9);
    while (got < count) {
      void *samples[16] = {0};
      dds_sample_info_t infos[16];
      int n = dds_take(reader, samples, infos, 16, 16);
      for (int i = 0; i < n; i++) {
        if (infos[i].valid_data) {
          print_RigSample((const tyre_msgs_msg_dds__RigSample_ *)samples[i]);
          got++;
        }
      }
      if (n > 0) dds_return_loan(reader, samples, n);
      if (dds_time() > deadline) {
        rc = 2;
        break;
      }
      if (n <= 0) dds_sleepfor(DDS_MSECS(10));
    }
  } else if (strcmp(argv[1], "sample") == 0) {
    dds_entity_t topic = dds_create_topic(participant, &tyre_msgs_msg_dds__RigSample__desc, "rt/rig/sample", NULL, NULL);
    dds_entity_t writer = topic < 0 ? topic : dds_create_writer(participant, topic, qos, NULL);
    if (writer < 0) {
      printf("WRITER_REFUSED %s\n", dds_strretcode(writer));
      return 3;
    }
    dds_time_t deadline = dds_time() + (dds_duration_t)(atof(argv[4]) * 1e9);
    dds_publication_matched_status_t st = {0};
    while (st.current_count == 0 && dds_time() < deadline) {
      dds_sleepfor(DDS_MSECS(20));
      dds_get_publication_matched_status(writer, &st);
    }
    if (st.current_count == 0) {
      printf("NO_READER\n");
      rc = 2;
    } else {
      dds_sleepfor(DDS_MSECS(500)); /* the reader's side of the key exchange */
      tyre_msgs_msg_dds__RigSample_ s;
      memset(&s, 0, sizeof s);
      s.header.frame_id = "iso_w";
      for (long i = 0; i < count; i++) {
        s.header.stamp.sec = (int32_t)i;
        s.seq = (uint64_t)i;
        s.fx_n = (double)i + 0.5;
        dds_write(writer, &s);
        dds_sleepfor(DDS_MSECS(20));
      }
      dds_sleepfor(DDS_MSECS(500));
      printf("SENT %ld\n", count);
    }
  } else {
    dds_entity_t topic = dds_create_topic(participant, &tyre_msgs_msg_dds__ProcedureCommand__desc,
                                          "rt/rig/procedure/command", NULL, NULL);
    dds_entity_t writer = topic < 0 ? topic : dds_create_writer(participant, topic, qos, NULL);
    if (writer < 0) {
      printf("WRITER_REFUSED %s\n", dds_strretcode(writer));
      return 3;
    }
    tyre_msgs_msg_dds__ProcedureCommand_ cmd;
    memset(&cmd, 0, sizeof cmd);
    cmd.command = 3; /* ABORT */
    cmd.header.frame_id = "";
    cmd.procedure = "";
    cmd.operator_name = argv[4];
    for (long i = 0; i < count; i++) {
      dds_write(writer, &cmd);
      dds_sleepfor(DDS_MSECS(100));
    }
    dds_publication_matched_status_t st;
    dds_get_publication_matched_status(writer, &st);
    printf("SENT %ld MATCHED %u\n", count, (unsigned)st.current_count);
  }
  dds_delete_qos(qos);
  dds_delete(participant);
  return rc;
}
