// noctua vocab: trains a place-recognition vocabulary (place::TrainVocabularyFromImages).
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "method_options.h"
#include "noctua/place/train.h"
#include "noctua/util/timer.h"

namespace noctua::app {
namespace {

struct VocabArguments {
  std::vector<std::string> inputs;
  MethodFlags method;
  place::VocabularyTraining training;
  std::string out;
};

void RunVocab(VocabArguments args) {
  place::VocabularyTraining& training = args.training;
  training.inputs.assign(args.inputs.begin(), args.inputs.end());
  training.method = args.method.method;
  training.method_config = MethodConfigFromFlags(args.method);
  training.progress = [](int done, int count) {
    if (done % 20 == 0 || done == count) {
      std::fprintf(stderr, "vocab: extracted %d/%d images\n", done, count);
    }
  };
  training.Check();
  Stopwatch watch;
  const place::Vocabulary vocabulary = place::TrainVocabularyFromImages(training);
  vocabulary.Save(args.out);
  std::cout << "vocab: " << vocabulary.num_words() << " words (k " << vocabulary.branching()
            << ", L " << vocabulary.levels() << ") from " << vocabulary.training_images()
            << " images in " << watch.ElapsedMs() / 1000.0 << " s\n"
            << "vocab: wrote " << args.out << ", identity " << vocabulary.identity() << "\n";
}

}  // namespace

void AddVocabCommand(CLI::App& app) {
  auto args = std::make_shared<VocabArguments>();
  CLI::App* command = app.add_subcommand(
      "vocab",
      "Train a place-recognition vocabulary (bag of binary words) from images, for the SLAM's "
      "relocalisation (docs/slam.md, Place recognition)");
  command
      ->add_option("images", args->inputs,
                   "Images, folders of images, or sequence folders (their rgb/ is used)")
      ->required();
  args->method.method = "orb";
  AddMethodFlags(*command, args->method);
  place::VocabularyOptions& vocabulary = args->training.vocabulary;
  command->add_option("-k,--k", vocabulary.branching, "Branching factor of the tree")
      ->capture_default_str();
  command->add_option("-L,--levels", vocabulary.levels, "Depth of the tree (up to k^L words)")
      ->capture_default_str();
  command
      ->add_option("--max-images", args->training.max_images,
                   "At most this many images, evenly spaced over the inputs (0: all)")
      ->capture_default_str();
  command->add_option("--seed", vocabulary.seed, "Seed of the clustering (same seed: same file)")
      ->capture_default_str();
  command->add_option("-o,--out", args->out, "Vocabulary file to write")->required();
  command->callback([args] { RunVocab(*args); });
}

}  // namespace noctua::app
