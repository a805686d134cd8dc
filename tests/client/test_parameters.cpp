// Parameter metadata on the client side: check_parameters() against a
// WELCOME 1.1 table, Connection::open_session failing locally (nothing sent)
// with a 1.1 server and sending as before to a 1.0 server, and the tables
// as `dn pipelines` / `dn ping` print them.
#include <gtest/gtest.h>

#include <cmath>

#include "args.hpp"
#include "commands.hpp"
#include "dn/client/client.hpp"
#include "fake_server.hpp"
#include "server_info.hpp"

namespace {

using namespace dn;
using namespace dn::protocol;
using dn::test::FakeServer;
using dn::test::Peer;

client::ConnectOptions opts() {
  client::ConnectOptions o;
  o.auth_token = "";
  o.connect_timeout = std::chrono::milliseconds(5000);
  o.io_timeout = std::chrono::milliseconds(5000);
  return o;
}

client::SessionDesc svgf_desc() {
  client::SessionDesc d;
  d.width = 4;
  d.height = 3;
  d.pipeline = "svgf";
  d.channel(ChannelId::Radiance).channel(ChannelId::Albedo);
  return d;
}

// The error check_parameters throws for `desc` against test_welcome_with_parameters().
client::Error rejection(const client::SessionDesc& desc) {
  try {
    client::check_parameters(test::test_welcome_with_parameters(), desc);
  } catch (const client::Error& e) {
    return e;
  }
  ADD_FAILURE() << "accepted";
  return client::Error::usage("accepted");
}

TEST(CheckParameters, UnknownNameListsTheValidNames) {
  const client::Error e = rejection(svgf_desc().parameter("alpha_colour", 0.1).parameter("alpha", 0.2));
  EXPECT_EQ(e.kind(), client::ErrorKind::Usage);
  EXPECT_EQ(e.code(), ErrorCode::InvalidParameter);
  EXPECT_EQ(e.field(), "OPEN_SESSION.parameters[1].name");
  EXPECT_EQ(e.server_message(),
            "pipeline 'svgf' has no parameter 'alpha'; valid names: alpha_colour, atrous_iterations");
  EXPECT_EQ(std::string(e.what()),
            "client error InvalidParameter at OPEN_SESSION.parameters[1].name: pipeline 'svgf' has no parameter "
            "'alpha'; valid names: alpha_colour, atrous_iterations");
}

TEST(CheckParameters, OutOfRangeNamesValueAndRange) {
  client::Error e = rejection(svgf_desc().parameter("atrous_iterations", 12));
  EXPECT_EQ(e.code(), ErrorCode::InvalidParameter);
  EXPECT_EQ(e.field(), "OPEN_SESSION.parameters[0].value");
  EXPECT_EQ(e.server_message(), "parameter 'atrous_iterations' of pipeline 'svgf' is 12, outside its range [0, 8]");
  e = rejection(svgf_desc().parameter("alpha_colour", -0.5));
  EXPECT_EQ(e.server_message(), "parameter 'alpha_colour' of pipeline 'svgf' is -0.5, outside its range [0, 1]");
  e = rejection(svgf_desc().parameter("alpha_colour", std::nan("")));
  EXPECT_EQ(e.field(), "OPEN_SESSION.parameters[0].value");
  EXPECT_NE(e.server_message().find("nan, outside its range [0, 1]"), std::string::npos) << e.server_message();
}

TEST(CheckParameters, IntegerParameterRejectsFractions) {
  const client::Error e = rejection(svgf_desc().parameter("atrous_iterations", 2.5));
  EXPECT_EQ(e.field(), "OPEN_SESSION.parameters[0].value");
  EXPECT_EQ(e.server_message(),
            "parameter 'atrous_iterations' of pipeline 'svgf' is 2.5, but must be an integer in [0, 8]");
}

TEST(CheckParameters, BoundsAreInclusiveAndRealParametersTakeFractions) {
  const Welcome w = test::test_welcome_with_parameters();
  EXPECT_NO_THROW(client::check_parameters(w, svgf_desc().parameter("atrous_iterations", 0)));
  EXPECT_NO_THROW(client::check_parameters(w, svgf_desc().parameter("atrous_iterations", 8)));
  EXPECT_NO_THROW(client::check_parameters(w, svgf_desc().parameter("alpha_colour", 0.125)));
  EXPECT_NO_THROW(client::check_parameters(w, svgf_desc()));
}

TEST(CheckParameters, TwiceAndPipelineWithoutParameters) {
  client::Error e = rejection(svgf_desc().parameter("alpha_colour", 0.1).parameter("alpha_colour", 0.2));
  EXPECT_EQ(e.field(), "OPEN_SESSION.parameters[1].name");
  EXPECT_EQ(e.server_message(), "parameter 'alpha_colour' is given twice");
  client::SessionDesc d = svgf_desc();
  d.pipeline = "passthrough";
  e = rejection(d.parameter("alpha_colour", 0.1));
  EXPECT_EQ(e.server_message(), "pipeline 'passthrough' takes no parameters, but 'alpha_colour' was given");
}

TEST(CheckParameters, NothingToCheckWithoutTablesOrForAnUnknownPipeline) {
  // A 1.0 server: the server checks.
  EXPECT_NO_THROW(client::check_parameters(test::test_welcome(), svgf_desc().parameter("alpha", 99)));
  // An unknown pipeline is the server's UNKNOWN_PIPELINE to report.
  client::SessionDesc d = svgf_desc();
  d.pipeline = "nope";
  EXPECT_NO_THROW(client::check_parameters(test::test_welcome_with_parameters(), d.parameter("alpha", 99)));
  EXPECT_EQ(client::find_parameters(test::test_welcome_with_parameters(), "nope"), nullptr);
  EXPECT_EQ(client::find_parameters(test::test_welcome(), "svgf"), nullptr);
  ASSERT_NE(client::find_parameters(test::test_welcome_with_parameters(), "svgf"), nullptr);
  EXPECT_EQ(client::find_parameters(test::test_welcome_with_parameters(), "svgf")->size(), 2u);
}

TEST(ClientParameters, OneOneServerTablesReachTheClientAndHelloSaysOneTwo) {
  uint8_t hello_minor = 0;
  FakeServer server([&](Peer& peer) {
    auto m = peer.recv();
    ASSERT_TRUE(m && std::holds_alternative<Hello>(m->message));
    hello_minor = m->header.version_minor;
    peer.send_welcome(test::test_welcome_with_parameters(), m->header.request_id);
    peer.recv(2000);  // until the client hangs up
  });
  auto conn = client::Connection::connect(server.url(), opts());
  ASSERT_TRUE(conn.welcome().has_parameters);
  const PipelineInfo* svgf = conn.find_pipeline("svgf");
  ASSERT_NE(svgf, nullptr);
  ASSERT_EQ(svgf->parameters.size(), 2u);
  EXPECT_EQ(svgf->parameters[1].name, "atrous_iterations");
  EXPECT_EQ(svgf->parameters[1].default_value, 4.0);
  EXPECT_EQ(svgf->parameters[1].max_value, 8.0);
  EXPECT_TRUE(svgf->parameters[1].integer);
  EXPECT_EQ(svgf->parameters[1].description, "Number of a-trous iterations.");
  conn.close();
  server.join();
  EXPECT_EQ(hello_minor, kVersionMinor);  // the client's own version
}

TEST(ClientParameters, MisspeltParameterFailsLocallyWithOneOneServer) {
  bool got_open = false;
  FakeServer server([&](Peer& peer) {
    peer.handshake_with(test::test_welcome_with_parameters());
    // The client gives up before sending: the next thing is its hang-up.
    auto m = peer.recv(5000);
    got_open = m && std::holds_alternative<OpenSession>(m->message);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  try {
    conn.open_session(svgf_desc().parameter("alpha", 0.2));
    ADD_FAILURE() << "open_session accepted a misspelt parameter";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Usage);
    EXPECT_EQ(e.code(), ErrorCode::InvalidParameter);
    EXPECT_NE(std::string(e.what()).find("valid names: alpha_colour, atrous_iterations"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(conn.is_open());  // a local failure leaves the connection usable
  conn.close();
  server.join();
  EXPECT_FALSE(got_open);
}

TEST(ClientParameters, OneZeroServerStillGetsTheRequestAndChecksIt) {
  OpenSession seen;
  FakeServer server([&](Peer& peer) {
    peer.handshake();  // a 1.0 server: no tables
    auto m = peer.recv();
    ASSERT_TRUE(m);
    auto* o = std::get_if<OpenSession>(&m->message);
    ASSERT_NE(o, nullptr);
    seen = *o;
    peer.send(Error{ErrorCode::InvalidParameter, "OPEN_SESSION.parameters[0].name",
                    "pipeline svgf has no parameter \"alpha\""},
              m->header.request_id);
    peer.recv(2000);
  });
  auto conn = client::Connection::connect(server.url(), opts());
  EXPECT_FALSE(conn.welcome().has_parameters);
  try {
    conn.open_session(svgf_desc().parameter("alpha", 0.2));
    ADD_FAILURE() << "expected the server's ERROR";
  } catch (const client::Error& e) {
    EXPECT_EQ(e.kind(), client::ErrorKind::Server);
    EXPECT_EQ(e.code(), ErrorCode::InvalidParameter);
    EXPECT_EQ(e.field(), "OPEN_SESSION.parameters[0].name");
  }
  conn.close();
  server.join();
  ASSERT_EQ(seen.parameters.size(), 1u);
  EXPECT_EQ(seen.parameters[0].name, "alpha");
}

// A hand-made WELCOME, and the report `dn pipelines` prints for it, written out in full.
Welcome report_welcome() {
  Welcome w;
  w.has_parameters = true;
  PipelineInfo acc{"acc", channel_bit(ChannelId::Radiance) | channel_bit(ChannelId::Albedo),
                   channel_bit(ChannelId::Emission), {}};
  acc.parameters = {{"k", 4.0, 1.0, 8.0, true, "Taps."}, {"longer_name", 0.05, 0.0, 1.0, false, "Blend."}};
  w.pipelines = {acc, {"pt", channel_bit(ChannelId::Radiance), 0, {}}};
  return w;
}

TEST(DnPipelines, ReportListsChannelsAndEveryParameterColumn) {
  EXPECT_EQ(cli::pipelines_report(report_welcome()),
            "acc\n"
            "  requires  radiance,albedo\n"
            "  optional  emission\n"
            "  parameters:\n"
            "    name         default  range   integer  description\n"
            "    k            4        [1, 8]  yes      Taps.\n"
            "    longer_name  0.05     [0, 1]  no       Blend.\n"
            "\n"
            "pt\n"
            "  requires  radiance\n"
            "  optional  -\n"
            "  parameters: none\n");
}

TEST(DnPipelines, ReportShowsKernelVariantsFromStats) {
  protocol::Stats stats;
  stats.values = {{"pipeline.acc.input_forms", 4}, {"pipeline.acc.kernel_variants", 7}, {"pipeline.pt.input_forms", 1}};
  const std::string report = cli::pipelines_report(report_welcome(), "", &stats);
  EXPECT_NE(report.find("acc\n  requires  radiance,albedo\n  optional  emission\n"
                        "  kernels   7 over 4 input forms (the warm-up compiles them all)\n  parameters:\n"),
            std::string::npos)
      << report;
  EXPECT_EQ(report.find("pt\n  requires  radiance\n  optional  -\n  kernels"), std::string::npos) << report;  // no count: no line
}

TEST(DnPipelines, OnePipelineOrAClearErrorAndOneZeroServers) {
  EXPECT_EQ(cli::pipelines_report(report_welcome(), "pt"),
            "pt\n  requires  radiance\n  optional  -\n  parameters: none\n");
  try {
    cli::pipelines_report(report_welcome(), "svgf");
    ADD_FAILURE() << "unknown pipeline accepted";
  } catch (const cli::UsageError& e) {
    EXPECT_EQ(std::string(e.what()), "the server offers no pipeline 'svgf'; it offers: acc, pt");
  }
  Welcome old = report_welcome();
  old.has_parameters = false;
  for (auto& p : old.pipelines) p.parameters.clear();
  EXPECT_NE(cli::pipelines_report(old, "acc").find("parameters: not announced (the server speaks protocol 1.0"),
            std::string::npos);
}

TEST(DnPing, ParameterNamesPerPipeline) {
  const Welcome w = report_welcome();
  EXPECT_EQ(cli::parameter_names(w, w.pipelines[0]), "k, longer_name");
  EXPECT_EQ(cli::parameter_names(w, w.pipelines[1]), "none");
  Welcome old = w;
  old.has_parameters = false;
  EXPECT_EQ(cli::parameter_names(old, old.pipelines[1]), "not announced (protocol 1.0 server)");
}

TEST(DnPipelines, RunsAgainstAServerAndRejectsBadOptions) {
  FakeServer server([&](Peer& peer) { peer.handshake_with(test::test_welcome_with_parameters()); });
  EXPECT_EQ(cli::run_pipelines({"--server", server.url(), "--pipeline", "svgf"}), 0);
  server.join();
  EXPECT_THROW(cli::run_pipelines({"--bogus"}), cli::UsageError);
  EXPECT_EQ(cli::run_pipelines({"--help"}), 0);
}

}  // namespace
